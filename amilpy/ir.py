"""The checked, sorted model that the compiler and the runner read.

`check` builds it from the syntax; nothing here refers back to the listing's
text except through spans (for messages). Expressions are `syntax` expressions
plus the four node kinds below, which stand for the simulation functions whose
value is not a plain function of their arguments; `EXPRESSIONS` is the whole
family a complete visitor of IR expressions handles.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

from . import syntax
from .diagnostics import Span
from .syntax import Expr, Node


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

    def __str__(self) -> str:
        return self.value


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


# every expression node a later stage may meet
EXPRESSIONS: tuple[type[Node], ...] = syntax.EXPRESSIONS + (SwitchValue, MemoryValue,
                                                            TableLookup, Impulse)


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


@dataclass(frozen=True)
class Switch:
    index: int
    func: str  # canonical name: FCNSW, INSW, OUTSW, COMPAR, LIMIT, DEADSP, QNTZR,
    #            STEP, RAMP, SINE, AND, IOR, NOR, NAND, EOR, NOT, EQUIV
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
    # names -> where defined, for reports and hints
    spans: dict[str, Span] = field(default_factory=dict)
    data_kinds: dict[str, str] = field(default_factory=dict)  # PARAM, CONST or INCON
    # compiled functions per set of constants: repeated runs do not recompile
    compiled: dict = field(default_factory=dict, repr=False, compare=False)
    # INITIAL values per set of data, output grids per timer: likewise
    memo: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def variables(self) -> list[str]:
        """Every named quantity of DYNAMIC a run records (states and algebraic)."""
        names = [s.name for s in self.states if not s.hidden]
        names += [e.target for e in self.dynamic]
        return names
