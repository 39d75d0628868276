"""The checked, sorted model that the compiler and the runner read.

`check` builds it from the syntax; nothing here refers back to the listing's
text except through spans (for messages). Expressions are `syntax` expressions
plus the four node kinds below, which stand for the simulation functions whose
value is not a plain function of their arguments; `EXPRESSIONS` is the whole
family a complete visitor of IR expressions handles.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import Enum

from .diagnostics import Span
from .parse import syntax
from .parse.syntax import Expr, Node


class SurfaceKind(str, Enum):
    """How a surface's value selects a branch."""

    SIGN = "sign"  # mode -1, 0 or +1
    LEVEL = "level"  # QNTZR: mode is the integer level k, the surface is X/P

    def __str__(self) -> str:
        return self.value


class Purpose(str, Enum):
    """What a surface is for."""

    SWITCH = "switch"  # selects a branch of a switch (or MODINT's mode)
    MEMORY = "memory"  # a memory function's condition
    FINISH = "finish"  # FINISH X = value: ends the run when crossed
    TERMT = "termt"  # TERMT(expr): ends the run when it turns positive
    # a crossing that runs written-order code: SCHEDULE s .XP./.XN./.XZ. e (ACSL's
    # DISCRETE s), or an EVENT's ZEROCONDITION e (FST's NEWVALUEs)
    SCHEDULE = "schedule"

    def __str__(self) -> str:
        return self.value

    @property
    def stops(self) -> bool:
        """The run loop ends its step where such a surface is crossed."""
        return self in (Purpose.FINISH, Purpose.TERMT, Purpose.SCHEDULE)


class Depends(str, Enum):
    """What a surface's value moves with (classified by `surfaces.classify`)."""

    CONST = "const"  # fixed for the whole run: not watched
    TIME = "time"  # TIME and constants only: breakpoints
    STATE = "state"  # the states: an event to locate
    IMPULSE = "impulse"  # reads IMPULS, which is nonzero only at breakpoints

    def __str__(self) -> str:
        return self.value

# -------------------------------------------------- expression nodes of the IR


@dataclass(frozen=True)
class SwitchValue(Node):
    """The value of switch instance `switch` (output `output` for OUTSW)."""

    switch: int
    span: Span
    output: int = 0


@dataclass(frozen=True)
class MemoryValue(Node):
    """The value of memory-function instance `memory` (HSTRSS, ZHOLD, ...)."""

    memory: int
    span: Span


@dataclass(frozen=True)
class TableLookup(Node):
    """AFGEN (linear) or NLFGEN (quadratic) interpolation in a FUNCTION table."""

    table: str
    x: Expr
    func: str  # the run-time interpolation (library entry's `lookup`: AFGEN, NLFGEN)
    span: Span
    written: str = ""  # the function's name as the listing writes it
    child_fields = ("x",)


@dataclass(frozen=True)
class Impulse(Node):
    """IMPULS(P1, P2): 1 exactly at t = P1 + k*P2, else 0 (see library)."""

    start: Expr
    period: Expr
    span: Span
    child_fields = ("start", "period")


@dataclass(frozen=True)
class UnitValue(Node):
    """The value of `name` after sorting unit `unit` (an IF or PROCEDURAL block of
    sorted code) has run: the unit computes all its outputs at once."""

    unit: int
    name: str
    span: Span


# every expression node a later stage may meet
EXPRESSIONS: tuple[type[Node], ...] = syntax.EXPRESSIONS + (SwitchValue, MemoryValue,
                                                            TableLookup, Impulse, UnitValue)


# ------------------------------------------- statements of written-order code
# (INITIAL, DYNAMIC's own statements, DISCRETE and TERMINAL in ACSL form, and the
# bodies of sorting units). Their expressions are IR expressions.


@dataclass(frozen=True)
class Let(Node):
    """NAME = expr; `store` says how the value is kept: REAL, INTEGER (truncated
    toward 0) or LOGICAL (1.0 if true, else 0.0)."""

    target: str
    expr: Expr
    span: Span
    store: str = "REAL"
    child_fields = ("expr",)


@dataclass(frozen=True)
class IfThen(Node):
    """(condition, statements) pairs, the first true one runs; a None condition is ELSE."""

    branches: tuple[tuple[Expr | None, tuple[Node, ...]], ...]
    span: Span

    def children(self) -> tuple[Node, ...]:
        out: list[Node] = []
        for cond, body in self.branches:
            if cond is not None:
                out.append(cond)
            out.extend(body)
        return tuple(out)


@dataclass(frozen=True)
class ForLoop(Node):
    """var = start, stop, step (bounds read once; at most language.MAX_LOOP times)."""

    var: str
    start: Expr
    stop: Expr
    step: Expr
    body: tuple[Node, ...]
    span: Span

    def children(self) -> tuple[Node, ...]:
        return (self.start, self.stop, self.step) + self.body


@dataclass(frozen=True)
class ScheduleAt(Node):
    """SCHEDULE section .AT. when (valued now)."""

    section: str
    when: Expr
    span: Span
    child_fields = ("when",)


@dataclass(frozen=True)
class TermtIf(Node):
    """TERMT in written-order code: the run ends after this code when cond is true."""

    cond: Expr
    index: int  # into Model.termts
    span: Span
    child_fields = ("cond",)


@dataclass(frozen=True)
class Solve(Node):
    """CSMP III's IMPL: `target` = `result`(target) solved by fixed-point iteration
    from `start` (the last accepted value): `body` computes `result` from the target,
    until |result - target| <= tol*max(1, |target|), at most IMPL_ITERATIONS times."""

    target: str
    start: Expr
    tol: Expr
    result: str
    body: tuple[Node, ...]
    span: Span

    def children(self) -> tuple[Node, ...]:
        return (self.start, self.tol) + self.body


IMPL_ITERATIONS = 50  # contract section 13

CODE: tuple[type[Node], ...] = (Let, IfThen, ForLoop, ScheduleAt, TermtIf, Solve)


# ---------------------------------------------------------------- instances


@dataclass(frozen=True)
class Surface:
    """A continuous function of (TIME, states) whose sign selects a branch.

    Switches whose surfaces are the same expression (and kind and purpose) share
    one Surface: a run has one mode for it, whichever statement it stands in.
    """

    index: int
    expr: Expr
    kind: SurfaceKind
    owner: int | None  # the first switch or memory instance; None for FINISH/TERMT
    purpose: Purpose
    depends: Depends
    span: Span
    description: str
    text: str = ""  # the expression as the listing writes it ("W1", "TIME - T1")
    # where the program reads it only on some branches of IF blocks (an ELSE IF's test,
    # a switch inside a THEN): the condition of those branches, a test of the modes of
    # surfaces before it (None: read always). Elsewhere it is not evaluated: its value
    # there may be a fault (1/X in an ELSE IF after IF (X == 0)) the program never meets
    guard: Expr | None = None


@dataclass(frozen=True)
class Switch:
    index: int
    func: str  # canonical name: FCNSW, INSW, OUTSW, COMPAR, LIMIT, DEADSP, QNTZR,
    #            STEP, RAMP, SINE, AND, IOR, NOR, NAND, EOR, NOT, EQUIV, the relations
    #            (.GT., ...), ABS, SIGN, AMAX1, AMIN1, DIM, AINT, NINT, AMOD
    args: tuple[Expr, ...]
    surfaces: tuple[int, ...]
    span: Span
    target: str
    written: str = ""  # the name as the listing writes it (FSW for FCNSW)


@dataclass(frozen=True)
class Memory:
    index: int
    func: str  # HSTRSS, ZHOLD, RST, PULSE, DERIV
    args: tuple[Expr, ...]
    slot: int  # first index in the memory vector z
    nslots: int
    surfaces: tuple[int, ...]
    span: Span
    target: str
    written: str = ""


@dataclass(frozen=True)
class State:
    name: str  # a model name, or a hidden one like "INTGRL#2" for nested calls
    ic: Expr
    deriv: Expr
    span: Span
    hidden: bool = False
    # MODINT: the reset to IC while `reset_surfaces[1]` > 0 (and `reset_surfaces[0]`
    # <= 0) is the runner's.
    reset_surfaces: tuple[int, ...] = ()
    # the state integrates while `runs` holds (a library template over the modes of
    # `modes`, M0, M1, ...), else its derivative is 0: MODINT's hold, LIMINT's bounds
    modes: tuple[int, ...] = ()
    runs: str = ""
    # (value, when): the runner puts the state on value while `when` (a template over
    # the modes of `modes`) holds, at each restart and step point (LIMINT's bounds)
    onto: tuple[tuple[Expr, str], ...] = ()


@dataclass(frozen=True)
class Equation:
    target: str
    expr: Expr
    span: Span


@dataclass(frozen=True)
class Unit:
    """An IF or PROCEDURAL block of sorted code: one sorting unit. Its outputs are
    the names it assigns (each an Equation whose value is a `UnitValue`), its
    inputs the names it reads; inside, the statements run in written order. An
    output a path does not assign keeps its value from before (`priors`)."""

    index: int
    kind: str  # IF or PROCEDURAL
    outputs: tuple[str, ...]
    inputs: tuple[str, ...]
    body: tuple[Node, ...]
    span: Span


@dataclass(frozen=True)
class Code:
    """Written-order code of one section (ACSL INITIAL, DYNAMIC, a DISCRETE,
    TERMINAL): names may be reassigned; `assigned` in order of first assignment."""

    section: str
    body: tuple[Node, ...]
    assigned: tuple[str, ...]
    span: Span | None


@dataclass(frozen=True)
class Discrete:
    """DISCRETE name ... END, with INTERVAL v = dt when it has one."""

    name: str
    code: Code
    interval: str | None  # the INTERVAL variable
    interval_value: Expr | None
    span: Span


@dataclass(frozen=True)
class FstEvent:
    """FST's EVENT: its code (the event's own values, then the NEWVALUEs, all from the
    values before it, given at once to states and SET variables) runs where the
    ZEROCONDITION surface reaches zero from either side (a located crossing; in
    step-point mode the first step point where it has), or, a time event, at FIRSTTIME
    (`first`, a value before the run) and then at each NEXTTIME (`next`: the name the
    code gives that value, None: once)."""

    surface: int | None
    first: Expr | None
    next: str | None
    code: Code
    span: Span


@dataclass(frozen=True)
class Termination:
    """A TERMT: where it stands (DERIVATIVE: located; else tested when its code runs),
    its condition as written and its message."""

    section: str
    text: str
    message: str | None
    span: Span


@dataclass
class Acsl:
    """What a program in ACSL form adds to the model (contract sections 9-11)."""

    initial: list[Code]  # in file order
    dynamic: Code  # DYNAMIC's own statements, run at every CINT instant
    discretes: dict[str, Discrete]
    terminal: list[Code]
    discrete_vars: list[str]  # names written-order code keeps between instants (z slots)
    cint_name: str
    cint: Expr  # the value CINTERVAL gives (before INITIAL may reassign it)
    t0: float
    termts: list[Termination]
    # the DISCRETE section each SCHEDULE .XP./.XN./.XZ. surface runs, and the crossing
    # direction (+1 XP, -1 XN, 0 XZ)
    crossings: dict[int, tuple[str, int]] = field(default_factory=dict)
    # names assigned in INITIAL and again in DERIVATIVE: their INITIAL value is the
    # value an IF unit keeps on a path that does not assign them
    priors: set[str] = field(default_factory=set)
    stores: dict[str, str] = field(default_factory=dict)  # declared INTEGER / LOGICAL
    functions: dict[str, object] = field(default_factory=dict)  # FUNCTION definitions
    bounded: bool = False  # a TERMT or TIMER FINTIM bounds the run
    # ALGORITHM, NSTEPS, MAXTERVAL, MINTERVAL -> the constant that holds its value
    controls: dict[str, str] = field(default_factory=dict)
    control_spans: dict[str, Span] = field(default_factory=dict)


@dataclass(frozen=True)
class Report:
    kind: str  # PRINT, OUTPUT, RANGE, PREPARE
    names: tuple[str, ...]
    label: str | None
    span: Span
    printer: bool = False  # PRTPLT: a figure and a line-printer plot in the printout
    x: str | None = None  # OUTPUT Y1, Y2 VS X: plotted against X instead of TIME


@dataclass
class RunSpec:
    """Everything that may change from one run to the next."""

    label: str
    data: dict[str, float]  # PARAM/CONST/INCON values
    changed: dict[str, float]  # what makes this run differ from the first
    tables: dict[str, tuple[tuple[float, ...], tuple[float, ...]]]
    timer: dict[str, float]  # FINTIM, DELT, PRDEL, OUTDEL, DELMIN, DELMAX as given
    method: str | None
    relerr: float | None
    abserr: float | None
    relerr_each: dict[str, float] = field(default_factory=dict)
    abserr_each: dict[str, float] = field(default_factory=dict)
    reports: list[Report] = field(default_factory=list)
    titles: list[str] = field(default_factory=list)
    # step-point mode as the listing asks it (ALGORITHM IALG = 3, DRIVER = 'EUDRIV');
    # None: the method's default (routes.step_point_mode)
    step_point: bool | None = None
    timer_spans: dict[str, Span] = field(default_factory=dict)  # where each TIMER key is
    weather: object | None = None  # FST's WEATHER statements (weather.WeatherSpec)
    # constants that size an array or bound a loop written out over one (parse.arrays)
    fixed: frozenset[str] = frozenset()

    def overridden(self, values: dict[str, float]) -> RunSpec:
        """This run with data values from outside (--set, a sweep, an ensemble's
        draw): they count as changed, and the label names every changed value."""
        if not values:
            return self
        fixed = sorted(set(values) & self.fixed)
        if fixed:
            from .diagnostics import Diagnostic, UsageError

            raise UsageError([Diagnostic(
                f"{fixed[0]} sizes an array or bounds a loop over one: it is fixed when the "
                "listing is read", None, f"change {fixed[0]} in the listing itself")])
        changed = {**self.changed, **values}
        label = ", ".join(f"{n} = {v:g}" for n, v in changed.items())
        return replace(self, data={**self.data, **values}, changed=changed,
                       label=label or self.label)


@dataclass
class Model:
    """A checked program: sorted equations, states, switches, and its runs."""

    name: str
    path: str | None
    source: str
    initial: list[Equation]  # sorted
    dynamic: list[Equation]  # sorted algebraic equations
    terminal: list[Equation]  # in written order
    states: list[State]
    switches: list[Switch]
    surfaces: list[Surface]
    memories: list[Memory]
    runs: list[RunSpec]
    data_names: list[str]
    units: list[Unit] = field(default_factory=list)  # IF/PROCEDURAL blocks of DYNAMIC
    terminal_code: list[Code] = field(default_factory=list)  # TERMINAL with IF/DO blocks
    acsl: Acsl | None = None  # the ACSL form's sections and events
    # FST's EVENT blocks, and its SET variables (kept between events, like states)
    events: list[FstEvent] = field(default_factory=list)
    sets: list[str] = field(default_factory=list)
    own_pi: bool = False  # an FST or ACSL listing's own PI (`syntax.Program.own_pi`): no pi given
    # the TERMT surfaces of a routine's STOP or FATALERR: a run they stop ends the job
    # (Fortran's STOP ends the program: no later run is made)
    ending: frozenset[int] = frozenset()
    # notes for the listing (read before any value, == tested pointwise, ...)
    warnings: list = field(default_factory=list)
    # names -> where defined, for reports and hints
    spans: dict[str, Span] = field(default_factory=dict)
    data_kinds: dict[str, str] = field(default_factory=dict)  # PARAM, CONST or INCON
    # FST's WEATHER: the weather names the model reads (a table each, filled per run
    # from the CABO files: `WEATHER_TABLE + name`), and the lines that read them
    weather: list[str] = field(default_factory=list)
    weather_lines: list[Span] = field(default_factory=list)
    # TERMT/FINISH surfaces whose condition holds at zero too (T >= TSTOP): where a
    # step point lands exactly on it (step-point mode), the run stops there
    closed: set[int] = field(default_factory=set)
    # generated functions per set of constants: repeated runs do not recompile
    compiled: dict = field(default_factory=dict, repr=False, compare=False)
    # INITIAL values per set of data, output grids per timer: likewise
    memo: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def variables(self) -> list[str]:
        """Every named quantity of DYNAMIC a run records (states and algebraic, and in
        ACSL form the names written-order code keeps)."""
        names = [s.name for s in self.states if not s.hidden]
        names += [e.target for e in self.dynamic]
        names += [n for n in self.kept if n not in names]
        return names

    @property
    def kept(self) -> list[str]:
        """The names code run at instants changes and the run keeps between them (in
        z, after the memory functions' slots): ACSL's written-order code's, FST's SET
        variables."""
        return self.acsl.discrete_vars if self.acsl is not None else self.sets
