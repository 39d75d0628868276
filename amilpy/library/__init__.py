"""The functions a listing may call, each described once: one `Func` entry holds
its signature and documentation (for messages), kind, arity, value, switching
surfaces, states, memory slots with their initial values and their update after
an accepted step, and its run-time function. The checker lowers a call and the
compiler emits it by reading the entry; nothing else knows a function by name.

Kinds (the contract's sections 5 and 12):
  math    a smooth function of its arguments (SIN, SQRT, ATAN2, NOTNUL, ...)
  state   introduces states (INTGRL, REALPL, LEDLAG, CMPXPL, MODINT, LIMINT)
  switch  a branch selected by the sign of one or more surfaces (FSW, LIMIT, RSW, ...);
          Fortran's non-smooth arithmetic (SIGN, ABS, AMAX1/AMIN1, DIM, AINT, NINT,
          AMOD) is a switch too, with a plain form (`scalar`, `vector`) for where it is
          evaluated once
  time    a switch on TIME alone (STEP, RAMP, SINE/HARM, the PULSE train): its
          surfaces change sign at instants known before the run (breakpoints)
  memory  keeps values from the last accepted step (HSTRSS, BCKLSH, ZHOLD, RST, PULSE,
          DERIV, DELAY), and the random functions (GAUSS, UNIF, RNDGEN, OU), whose
          draws are held in memory between draw instants
  impulse IMPULS: 1 at t = P1 + k*P2, else 0
  table   AFGEN / NLFGEN / LINT interpolation in a FUNCTION table

Values, surfaces, states and memory updates are small templates in a Python
subset (`templates.py` parses and checks them once, at import). A name means:
A, B, ... the call's arguments; M0, M1, ... the modes of its surfaces (memory:
its conditions as the step saw them; N0, ... as they stand from now on); Y0,
Y1, ... its own states; Z0, Z1, ... its memory slots (Z: the whole memory
vector, OFFSET: its first slot, VALUE: its value; SEED, HOLD: the run's random seed and
how long a draw is held; SITE: the call site's number); TIME; INF; and calls of the
language's functions or of `runtime.HELPERS` (a surface may call a helper too:
PULSE's train). A template whose text starts with `*` gives several slots at once.

A signature names its arguments; `[, E]` marks optional ones at the end (a template
reads one the call leaves out as 0) and `...)` any number from the last named one on
(a switch's templates read the first two: a call with more is the function of the
first two, then of that and the next, and so on: AMAX1(A, B, C) is
AMAX1(AMAX1(A, B), C)).

A switch with a plain form means, with the modes its surfaces have on the spot
(`surfaces.sign`, `surfaces.level`), exactly what the plain form means, at the
edges too (tests/test_nonsmooth.py checks it): its templates are what the
integrator sees between crossings, the plain form what code that runs once reads.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import Enum
from functools import cache
from typing import Any

from ..ir import SurfaceKind
from . import runtime as rt
from .templates import check_template


class Kind(str, Enum):
    MATH = "math"
    STATE = "state"
    SWITCH = "switch"
    TIME = "time"
    MEMORY = "memory"
    IMPULSE = "impulse"
    TABLE = "table"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class StateSpec:
    """One state a function introduces: its initial value and derivative as
    templates, and the stem of its name when the listing does not name it."""

    ic: str
    deriv: str
    tag: str
    # the first state takes the assigned variable's name when the call is the
    # whole right-hand side (Y = REALPL(...)); LEDLAG's inside state never does
    named: bool = True
    # when the state integrates, over the modes of the function's surfaces (M0, ...);
    # else its derivative is 0 (MODINT holds, LIMINT stops at a bound)
    runs: str = ""
    # MODINT: the runner resets the state to IC while surface 1 > 0 and surface 0 <= 0
    resets: bool = False
    # where the runner puts the state while it is held there: (value over the
    # arguments, when over the modes), at each restart and step point (LIMINT's
    # bounds: a held state sits exactly on its bound, never a rounding beside it)
    onto: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class MemorySpec:
    """Values kept from the last accepted step, in slots of the memory vector z."""

    slots: str  # how many: a template over the (literal) arguments, e.g. "1" or "A + 6"
    initial: tuple[str, ...]  # one template per slot (or one `*` template for all)
    value: str  # the function's value from its slots and conditions
    update: tuple[str, ...]  # the slots after an accepted step
    # False: the slots change only where a run restarts anyway (an event), so a
    # chunked integrator need not stop at every step for them
    every_step: bool = True
    # the slot that holds a future instant at which the model switches (PULSE's end)
    wakes: int | None = None
    # the slot that holds the next instant at which the memory samples the trajectory
    # (DELAY's store): the loop evaluates the `update` templates there, inside each
    # accepted step, at the state the dense output gives (`ModelCode.sample`)
    samples: int | None = None
    # a template over the arguments: how far back the value reads (DELAY's delay);
    # where it is known before the run and the derivatives read the value, no step is
    # longer (each stage then reads a past the store holds)
    horizon: str = ""
    # the value reads the slots alone, never the arguments as they are now: a name
    # the arguments read may itself read the value without making a loop (.KEPT)
    delayed: bool = False
    # the value is a play (HSTRSS): between two updates it moves one way only, so
    # where the value the last update leaves would turn back inside a step (its
    # input reversing while it pushes), the step is cut there and the memory updated
    # at the turning point (`run.turns`), not at the step's end
    plays: bool = False
    # the slots (offsets, given how many there are) that keep instants and counts, not
    # values the arguments give: the sensitivity equations carry no slope in them
    clock: Callable[[int], list[int]] | None = None
    # (z, offset, slots, delay, ta, tb) -> the instants in (ta, tb) at which the value,
    # read `horizon` back, passes a point the slots keep: its slope jumps there, and so
    # the values' part of the field, which a tangent's step must not straddle
    knots: Callable[[list, int, int, float, float, float], list[float]] | None = None


@dataclass(frozen=True)
class Func:
    name: str
    kind: Kind
    signature: str  # "FCNSW(X, A, B, C)"; "AMAX1(X1, X2, ...)": any number from 2
    doc: str = ""
    aliases: tuple[str, ...] = ()
    # switches: one value template per output; surfaces as templates
    values: tuple[str, ...] = ()
    surfaces: tuple[str, ...] = ()
    surface_kind: SurfaceKind = SurfaceKind.SIGN
    # Fortran arithmetic (ABS, SIGN, MIN, AMOD...): a switch for the integrator's sake;
    # where only outputs read it, it is evaluated where it stands and makes no event
    arithmetic: bool = False
    states: tuple[StateSpec, ...] = ()
    memory: MemorySpec | None = None
    # the plain form (math functions, and the non-smooth switches where they are
    # evaluated once): the function on floats, and on NumPy arrays (a NumPy attribute
    # name, or a factory given the numpy module)
    scalar: Callable | None = None
    vector: str | Callable[[Any], Callable] | None = None
    # tables: the run-time interpolation (a `runtime.HELPERS` name)
    lookup: str = ""
    note: str = ""  # said with the signature when a call has the wrong arguments
    literal_args: tuple[int, ...] = ()  # positive integer literals (DELAY's N)
    constant_args: tuple[int, ...] = ()  # known before the run (initial values, DELAY's P)
    # constant arguments that must be > 0 / >= 0: checked with the data when the
    # listing is checked, else when the run's constants are known
    positive_args: tuple[int, ...] = ()
    nonnegative_args: tuple[int, ...] = ()
    # time functions: (first instant, period) templates over constant arguments; the
    # function's surfaces change sign only at first + k*period (k >= 0), which are
    # breakpoints (PULSE's train); an affine surface (STEP's TIME - P) needs none
    breaks: tuple[tuple[str, str], ...] = ()
    # tables: reads outside the table extend the end segments, with a warning (LINT)
    extends: bool = False
    # tables: which argument is the table and which the abscissa
    table_at: int = 0
    x_at: int = 1
    # other forms of the same name, told apart by their number of arguments
    variants: tuple[Func, ...] = field(default=())

    @property
    def arg_names(self) -> tuple[str, ...]:
        """The arguments' names in the signature ("X", "A", ...)."""
        return _names(self.signature[self.signature.index("(") + 1:-1])

    @property
    def nargs(self) -> tuple[int, int | None]:
        """(min, max) arguments, from the signature (max None: any number)."""
        n = len(self.arg_names)
        if self.signature.endswith("...)"):
            return n, None
        if "[" in self.signature:  # optional arguments at the end
            return len(_names(self.signature[self.signature.index("(") + 1:
                                             self.signature.index("[")])), n
        return n, n

    def argument_fault(self, i: int, value: float) -> str | None:
        """What is wrong with constant argument i's value, else None."""
        if i in self.positive_args and not value > 0:
            return f"{self.arg_names[i]} of {self.name} must be positive (got {value:g})"
        if i in self.nonnegative_args and not value >= 0:
            return f"{self.arg_names[i]} of {self.name} must not be negative (got {value:g})"
        return None

    @property
    def plain(self) -> bool:
        """Whether the function has a plain form: a function of its arguments alone,
        which code evaluated once (INITIAL, a test made where it stands) calls."""
        return self.scalar is not None

    @property
    def folds(self) -> bool:
        """A switch of any number of arguments: its templates read two (see the
        module's docstring)."""
        return self.kind is Kind.SWITCH and self.nargs[1] is None

    @property
    def outputs(self) -> int:
        return max(1, len(self.values)) if self.kind in (Kind.SWITCH, Kind.TIME) else 1

    def form(self, nargs: int) -> Func:
        """The variant that takes `nargs` arguments (itself if none does)."""
        for f in (self, *self.variants):
            lo, hi = f.nargs
            if lo <= nargs and (hi is None or nargs <= hi):
                return f
        return self

    def signatures(self) -> str:
        return " or ".join(f.signature for f in (self, *self.variants))

    def counts(self) -> str:
        """How many arguments the forms take, for a message: "3", "2 to 4", "at least
        2", "3, 4 or 5"."""
        forms = [f.nargs for f in (self, *self.variants)]
        if len(forms) == 1 or any(hi is None for _, hi in forms):
            lo, hi = forms[0]
            return f"{lo}" if hi == lo else (f"{lo} to {hi}" if hi else f"at least {lo}")
        n = sorted({k for lo, hi in forms for k in range(lo, hi + 1)})
        return str(n[0]) if len(n) == 1 else ", ".join(map(str, n[:-1])) + f" or {n[-1]}"


@cache
def _names(inner: str) -> tuple[str, ...]:
    inner = inner.replace("[", "").replace("]", "")
    return tuple(a.strip() for a in inner.split(",") if a.strip() not in ("", "..."))


FUNCTIONS: dict[str, Func] = {}
ALIASES: dict[str, str] = {}
_generation = [0]  # registrations so far: what is derived from FUNCTIONS is cached by it


def generation() -> int:
    """Changes whenever an entry is registered (a cache of the registry's views
    compares it)."""
    return _generation[0]


def register(func: Func) -> Func:
    """Add an entry (its templates are checked here: a bad one fails at import)."""
    for f in (func, *func.variants):
        check_template_set(f)
    FUNCTIONS[func.name] = func
    for alias in func.aliases:
        ALIASES[alias] = func.name
    _generation[0] += 1
    return func


def callable_names() -> set[str]:
    """Every name a listing may call (canonical and aliases); the relational
    switches the checker makes from `A > B` are not among them."""
    return {n for n in (*FUNCTIONS, *ALIASES) if not n.startswith(".")}


def lookup(name: str, nargs: int | None = None) -> Func | None:
    """The entry for a name as written (aliases too); with `nargs`, the form that
    takes that many arguments."""
    func = FUNCTIONS.get(ALIASES.get(name, name))
    if func is not None and nargs is not None:
        return func.form(nargs)
    return func


def check_template_set(f: Func) -> None:
    lo, hi = f.nargs
    n = hi if hi is not None else max(lo, 8)
    nstates, nsurf = len(f.states), len(f.surfaces)
    calls = frozenset(rt.HELPERS) | {n for n, g in FUNCTIONS.items() if g.plain}

    def check(text: str, **kw: Any) -> None:
        check_template(text, f.name, args=n, calls=calls, **kw)

    for t in f.surfaces:
        check(t, states=nstates, arithmetic=True)
    for first, period in f.breaks:
        check(first, arithmetic=True)
        check(period, arithmetic=True)
    for s in f.states:
        check(s.ic, arithmetic=True)
        check(s.deriv, states=nstates, arithmetic=True)
        if s.runs:
            check(s.runs, modes=nsurf)
        for value, when in s.onto:
            check(value, states=nstates, arithmetic=True)
            check(when, modes=nsurf)
    for v in f.values:
        check(v, modes=nsurf, states=nstates, arithmetic=f.kind is Kind.STATE)
    if f.memory is not None:
        mem = f.memory
        check(mem.slots, arithmetic=True)
        for t in mem.initial:
            check(t)
        check(mem.value, modes=nsurf, slots=True)
        for t in mem.update:
            check(t, modes=nsurf, slots=True, update=True)
        if mem.horizon:
            check(mem.horizon, arithmetic=True)


def runtime_name(func: Func) -> str:
    """The name generated code calls a plain form by: its own, or NAME_n for the
    variant of n arguments."""
    return func.name if FUNCTIONS.get(func.name) is func else f"{func.name}_{func.nargs[0]}"


def _plain_forms():
    for entry in FUNCTIONS.values():
        for f in (entry, *entry.variants):
            if f.plain:
                yield runtime_name(f), f


def math_functions() -> dict[str, Callable]:
    """Run-time name -> the function on floats, for every plain form."""
    return {name: f.scalar for name, f in _plain_forms()}


def vector_functions() -> dict[str, Callable]:
    """Every function generated code calls, elementwise on NumPy arrays."""
    import numpy as np

    out: dict[str, Callable] = {
        name: getattr(np, f.vector) if isinstance(f.vector, str) else f.vector(np)
        for name, f in _plain_forms()}
    out.update(rt.vector_helpers())
    return out


def _vector_sign(np):
    return lambda a, b: np.where(np.asarray(b) >= 0.0, np.abs(a), -np.abs(a))


def _vector_many(ufunc: str):
    import functools

    return lambda np: (lambda *args: functools.reduce(getattr(np, ufunc), args))


def _vector_dim(np):
    def dim(x, y):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        return np.where(x > y, x - y, 0.0)
    return dim


def _vector_nint(np):
    def nint(x):
        a = np.abs(np.asarray(x, dtype=float))
        n = np.floor(a)
        return np.copysign(np.where(a - n >= 0.5, n + 1.0, n), x)
    return nint


# --- mathematical (Fortran meanings) -----------------------------------------
def _math(signature: str, scalar: Callable, vector, *aliases: str, doc: str = "") -> None:
    register(Func(signature[:signature.index("(")], Kind.MATH, signature, doc, aliases,
                  scalar=scalar, vector=vector))


_math("SQRT(X)", rt.safe_sqrt, "sqrt", doc="NaN below 0")
_math("EXP(X)", rt.safe_exp, "exp")
_math("ALOG(X)", rt.safe_log, "log", "LOG", doc="natural logarithm")
_math("ALOG10(X)", rt.safe_log10, "log10", "LOG10")
# raw math functions: a domain fault (SIN of an infinity, ASIN(2)) raises
# ValueError, which the runner turns into a rejected step or a failure with the
# statement, and the constant evaluator into an error at the listing's line
_math("SIN(X)", math.sin, "sin")
_math("COS(X)", math.cos, "cos")
_math("TAN(X)", math.tan, "tan")
_math("ASIN(X)", math.asin, "arcsin")
_math("ACOS(X)", math.acos, "arccos")
_math("ATAN(X)", math.atan, "arctan")
_math("SINH(X)", rt.nan_on_domain(math.sinh), "sinh")
_math("COSH(X)", rt.nan_on_domain(math.cosh), "cosh")
_math("TANH(X)", math.tanh, "tanh")
_math("FLOAT(X)", float, lambda np: (lambda x: np.asarray(x, dtype=float)),
      "REAL", "DBLE", "SNGL", doc="X as a real number (Fortran's conversions)")
_math("ATAN2(Y, X)", math.atan2, "arctan2")
_math("POW(X, Y)", rt.safe_pow, "power", doc="X**Y (Magnolia's pow; NaN for a negative X "
      "to a fractional Y)")
_math("ELEMENT(K, X1, ...)", rt.element, rt.vector_element,
      doc="XK: an array's element at a subscript known only as the run goes (X[K], the "
      "reader's); K outside 1..n is a fault")
_math("NOTNUL(X)", rt.notnul, lambda np: (lambda x: np.where(np.asarray(x) == 0.0, 1.0, x)),
      doc="1 if X = 0, else X: Y/NOTNUL(X) never divides by 0")


# --- non-smooth arithmetic (Fortran meanings): switches in sorted code ------------
# Where the integrator evaluates them (DYNAMIC, DERIVATIVE) their kinks and jumps are
# switching surfaces like FSW's: crossings located, events listed, Filippov sliding
# where both sides push back (MT*SIGN(1.0, W) at rest). Where they are evaluated once
# their plain form runs. Kinks are sign surfaces (A - B for AMAX1, AMIN1 and DIM: one
# surface where both are written on the same arguments). Jumps are one LEVEL surface
# each, whose mode is the whole number k the value holds in a band: level(v) =
# ceil(v - 1/2) takes k on (k - 1/2, k + 1/2], so v = 0.5 - |X| gives k = -floor(|X|),
# exactly (|X| = 2 is band -2, where AINT is 2), and AINT is -k*sign(X). The sign is
# read on the spot: within a band other than 0, |X| >= 1 and X keeps its sign; in band
# 0 the value is 0 whatever the sign. X = 0 is the inner edge of band 0, which the
# surface (|X| there) touches and never crosses: no event where AINT does not jump.
def _nonsmooth(signature: str, scalar: Callable, vector, values: str, surfaces: tuple[str, ...],
               *aliases: str, doc: str, kind: SurfaceKind = SurfaceKind.SIGN) -> None:
    register(Func(signature[:signature.index("(")], Kind.SWITCH, signature, doc, aliases,
                  values=(values,), surfaces=surfaces, surface_kind=kind, arithmetic=True,
                  scalar=scalar, vector=vector))


_nonsmooth("ABS(X)", abs, "abs", "(-A if M0 < 0 else A)", ("A",), "IABS", doc="|X|")
_nonsmooth("SIGN(A, B)", rt.fortran_sign, _vector_sign,
           "((A if M0 >= 0 else -A) if M1 >= 0 else (-A if M0 >= 0 else A))", ("A", "B"),
           "ISIGN", doc="|A| if B >= 0, else -|A|")
_nonsmooth("AMAX1(X1, X2, ...)", max, _vector_many("maximum"), "(B if M0 < 0 else A)",
           ("A - B",), "MAX", "AMAX0", "MAX1", "MAX0", doc="the largest argument")
_nonsmooth("AMIN1(X1, X2, ...)", min, _vector_many("minimum"), "(A if M0 < 0 else B)",
           ("A - B",), "MIN", "AMIN0", "MIN1", "MIN0", doc="the smallest argument")
_nonsmooth("DIM(X, Y)", rt.fortran_dim, _vector_dim, "((A - B) if M0 > 0 else 0.0)",
           ("A - B",), "IDIM", doc="X - Y if X > Y, else 0")
_nonsmooth("AINT(X)", rt.fortran_aint, "trunc", "(-M0 * SGN(A))", ("0.5 - ABS(A)",), "INT",
           doc="truncation toward 0", kind=SurfaceKind.LEVEL)
# NINT: floor(|X| + 1/2) = -level(-|X|), halves away from 0
_nonsmooth("NINT(X)", rt.fortran_nint, _vector_nint, "(-M0 * SGN(A))", ("-ABS(A)",),
           "ANINT", doc="the nearest whole number, halves away from 0",
           kind=SurfaceKind.LEVEL)
# AMOD: A - B*AINT(A/B), AINT of A/B as above (B*SGN(A/B) is SGN(A)*|B|), computed
# as fmod while A/B is in the branch (`surfaces.amod_at`)
_nonsmooth("AMOD(A, B)", rt.fortran_amod, "fmod", "AMODAT(A, B, M0)",
           ("0.5 - ABS(A / B)",), "MOD", doc="remainder with the sign of A",
           kind=SurfaceKind.LEVEL)

# --- states -------------------------------------------------------------------
register(Func("INTGRL", Kind.STATE, "INTGRL(IC, X)", "Y = IC + integral of X",
              states=(StateSpec("A", "B", "INTGRL"),), values=("Y0",),
              note="the initial value comes first"))
register(Func("INTEG", Kind.STATE, "INTEG(X, IC)", "ACSL order: INTEG(X, IC)",
              states=(StateSpec("B", "A", "INTGRL"),), values=("Y0",),
              note="the derivative comes first, the initial value second (ACSL order)"))
register(Func("REALPL", Kind.STATE, "REALPL(IC, P, X)", "P*Y' + Y = X, Y(0) = IC",
              states=(StateSpec("A", "(C - Y0)/B", "REALPL"),), values=("Y0",)))
register(Func("LEDLAG", Kind.STATE, "LEDLAG(P1, P2, X)", "(P1*s + 1)/(P2*s + 1) applied to X",
              # the state z lags X by P2; the output is z + P1/P2*(X - z)
              states=(StateSpec("0.0", "(C - Y0)/B", "LEDLAG", named=False),),
              values=("Y0 + A/B*(C - Y0)",)))
register(Func("CMPXPL", Kind.STATE, "CMPXPL(IC1, IC2, P1, P2, X)",
              "Y'' + 2*P1*P2*Y' + P2**2*Y = X",
              states=(StateSpec("A", "Y1", "CMPXPL"),
                      StateSpec("B", "E - 2.0*C*D*Y1 - D*D*Y0", "CMPXPL'", named=False)),
              values=("Y0",)))
register(Func("MODINT", Kind.STATE, "MODINT(IC, X1, X2, X3)",
              "X1>0: integrate X3; else X2>0: reset to IC; else hold",
              # the state is held while surface 0 <= 0; the runner resets it to IC
              # while surface 1 > 0 (ir.State.reset_surfaces)
              states=(StateSpec("A", "D", "MODINT", runs="M0 > 0.0", resets=True),),
              surfaces=("B", "C"), values=("Y0",)))
register(Func("LIMINT", Kind.STATE, "LIMINT(YD, IC, BB, TB)",
              "integral of YD from IC, held within [BB, TB]: it stops at a bound while "
              "YD pushes it out, and leaves it when YD turns",
              # surfaces Y - BB, Y - TB (the bounds, located) and YD; the state stops
              # while (Y <= BB and YD < 0) or (Y >= TB and YD > 0)
              states=(StateSpec("B", "A", "LIMINT",
                                runs="((M0 > 0 or M2 >= 0) and (M1 < 0 or M2 <= 0))",
                                onto=(("C", "(M0 <= 0 and M2 < 0)"),
                                      ("D", "(M1 >= 0 and M2 > 0)"))),),
              surfaces=("Y0 - C", "Y0 - D", "A"), values=("Y0",)))

# --- switches -----------------------------------------------------------------
register(Func("FCNSW", Kind.SWITCH, "FCNSW(X, A, B, C)", "A if X<0; B if X=0; C if X>0",
              ("FSW",), values=("(B if M0 < 0 else (D if M0 > 0 else C))",), surfaces=("A",)))
register(Func("INSW", Kind.SWITCH, "INSW(X, A, B)", "A if X<0; B if X>=0",
              values=("(B if M0 < 0 else C)",), surfaces=("A",)))
register(Func("OUTSW", Kind.SWITCH, "OUTSW(X, V)", "X<0: (V, 0); X>=0: (0, V)",
              values=("(B if M0 < 0 else 0.0)", "(0.0 if M0 < 0 else B)"), surfaces=("A",)))
register(Func("COMPAR", Kind.SWITCH, "COMPAR(X1, X2)", "0 if X1<X2; 1 if X1>=X2",
              values=("(0.0 if M0 < 0 else 1.0)",), surfaces=("A - B",)))
register(Func("LIMIT", Kind.SWITCH, "LIMIT(P1, P2, X)", "min(P2, max(P1, X))", ("BOUND",),
              values=("(A if M0 < 0 else (B if M1 > 0 else C))",), surfaces=("C - A", "C - B")))
register(Func("DEADSP", Kind.SWITCH, "DEADSP(P1, P2, X)",
              "0 if P1<=X<=P2; X-P2 above; X-P1 below", ("DEAD",),
              values=("((C - B) if M1 > 0 else ((C - A) if M0 < 0 else 0.0))",),
              surfaces=("C - A", "C - B")))
register(Func("QNTZR", Kind.SWITCH, "QNTZR(P, X)", "P*k for (k-1/2)P < X <= (k+1/2)P",
              values=("(M0 * A)",), surfaces=("B / A",), surface_kind=SurfaceKind.LEVEL))
# ACSL's names for the same tests (a number is true when > 0)
_LOGIC_ALIASES = {"AND": ("REAAND",), "NOR": ("REANOR",)}
for _name, _value, _doc in (
    ("AND", "(1.0 if (M0 > 0 and M1 > 0) else 0.0)", "1 if X1>0 and X2>0, else 0"),
    ("IOR", "(1.0 if (M0 > 0 or M1 > 0) else 0.0)", "1 if X1>0 or X2>0, else 0"),
    ("NOR", "(0.0 if (M0 > 0 or M1 > 0) else 1.0)", "0 if X1>0 or X2>0, else 1"),
    ("NAND", "(0.0 if (M0 > 0 and M1 > 0) else 1.0)", "0 if X1>0 and X2>0, else 1"),
    ("EOR", "(1.0 if ((M0 > 0) != (M1 > 0)) else 0.0)", "1 if exactly one of X1, X2 > 0"),
    ("EQUIV", "(1.0 if ((M0 > 0) == (M1 > 0)) else 0.0)", "1 if both or neither > 0"),
):
    register(Func(_name, Kind.SWITCH, f"{_name}(X1, X2)", _doc, values=(_value,),
                  surfaces=("A", "B"), aliases=_LOGIC_ALIASES.get(_name, ())))
register(Func("NOT", Kind.SWITCH, "NOT(X)", "0 if X>0, else 1",
              values=("(0.0 if M0 > 0 else 1.0)",), surfaces=("A",)))
# the condition itself is the surface: a number is true when > 0, and a relational
# test (X > 0) is a switch whose value (1 or 0) is located where X crosses 0
register(Func("RSW", Kind.SWITCH, "RSW(C, A, B)", "A if C is true (> 0), else B",
              values=("(B if M0 > 0 else C)",), surfaces=("A",)))

# --- relational tests in sorted code (section 10): `A > B` is a switch on A - B ------
# Their names cannot be written as a call; the checker makes them from the operators.
RELATIONS: dict[str, str] = {"<": ".LT.", "<=": ".LE.", ">": ".GT.", ">=": ".GE."}
for _op, _name in RELATIONS.items():
    register(Func(_name, Kind.SWITCH, f"{_name}(A, B)", f"1 if A {_op} B, else 0",
                  values=(f"(1.0 if M0 {_op} 0 else 0.0)",), surfaces=("A - B",)))

# --- time switches (surface TIME - P: breakpoints known before the run) --------
register(Func("STEP", Kind.TIME, "STEP(P)", "0 for t<P; 1 for t>=P",
              values=("(0.0 if M0 < 0 else 1.0)",), surfaces=("TIME - A",)))
register(Func("RAMP", Kind.TIME, "RAMP(P)", "0 for t<P; t-P after",
              values=("(0.0 if M0 < 0 else TIME - A)",), surfaces=("TIME - A",)))
register(Func("SINE", Kind.TIME, "SINE(P1, P2, P3)", "0 for t<P1; sin(P2(t-P1)+P3) after",
              ("HARM",),  # ACSL's HARM(TZ, W, P): the same arguments in the same order
              values=("(0.0 if M0 < 0 else SIN(B*(TIME - A) + C))",), surfaces=("TIME - A",)))
register(Func("IMPULS", Kind.IMPULSE, "IMPULS(P1, P2)", "1 at t = P1 + k*P2"))

# --- memory (updated only on accepted steps) ------------------------------------
_HSTRSS = "AMIN1(D - B, AMAX1(D - C, Z0))"
register(Func("HSTRSS", Kind.MEMORY, "HSTRSS(IC, P1, P2, X)",
              "Y = min(X-P1, max(X-P2, prev)), Y(0)=IC", constant_args=(0,),
              memory=MemorySpec("1", ("A",), _HSTRSS, ("VALUE",), plays=True)))
register(Func("ZHOLD", Kind.MEMORY, "ZHOLD(X1, X2)", "X2 while X1>0 else prev",
              surfaces=("A",),
              memory=MemorySpec("1", ("0.0",), "(B if M0 > 0.0 else Z0)", ("VALUE",),
                                every_step=False)))
register(Func("RST", Kind.MEMORY, "RST(X1, X2, X3)", "reset-set flip-flop",
              surfaces=("A", "B", "C"),
              memory=MemorySpec(
                  "1", ("0.0",),
                  "(0.0 if M0 > 0 else (1.0 if M1 > 0 else ((1.0 - Z0) if M2 > 0 else Z0)))",
                  ("VALUE",))))
register(Func("PULSE", Kind.MEMORY, "PULSE(P, X)", "Y=1 for at least P from X>0",
              surfaces=("B",),
              # Z0 is the instant the pulse ends; a trigger starts a new one
              memory=MemorySpec("1", ("-INF",), "(1.0 if TIME < Z0 else 0.0)",
                                ("((TIME + A) if (N0 > 0.0 and TIME >= Z0) else Z0)",),
                                every_step=False, wakes=0),
              variants=(
                  # ACSL's pulse train: on at TZ + k*P for W
                  Func("PULSE", Kind.TIME, "PULSE(TZ, P, W)",
                       "1 for TZ + k*P <= t < TZ + k*P + W (k = 0, 1, ...), else 0",
                       values=("(1.0 if M0 > 0 else 0.0)",),
                       surfaces=("PULSE_ON(TIME, A, B, C)",),
                       breaks=(("A", "B"), ("A + C", "B")),
                       constant_args=(0, 1, 2), positive_args=(1,), nonnegative_args=(2,)),
              )))
_BACKLASH = "AMIN1(C + B, AMAX1(C - B, Z0))"
register(Func("BCKLSH", Kind.MEMORY, "BCKLSH(IC, DL, X)",
              "backlash of total width 2*DL: HSTRSS(IC, -DL, DL, X)", constant_args=(0,),
              memory=MemorySpec("1", ("A",), _BACKLASH, ("VALUE",), plays=True)))
register(Func("DERIV", Kind.MEMORY, "DERIV(IC, X)", "dX/dt, Y(0)=IC", ("DERIVT",),
              constant_args=(0,),
              # (x1, t1) the newest accepted point, (x2, t2) the one before, the value
              memory=MemorySpec("5", ("0.0", "0.0", "0.0", "0.0", "A"),
                                "DERIV(B, TIME, Z0, Z1, Z2, Z3, Z4)",
                                ("B", "TIME", "Z0", "Z1", "VALUE"))))
# DELAY's store (runtime.delay_store): a ring of (t, X) samples, K = N + 2 (NMX + 2) of
# them, one spacing apart: the loop samples X from its dense output at every instant
# the store asks for (slot DELAY_NEXT), the update after a step records the step's end
register(Func("DELAY", Kind.MEMORY, "DELAY(N, P, X)",
              "X(t0) for t < t0+P, else X(t-P) from N points stored over P, interpolated",
              literal_args=(0,), constant_args=(1,),
              memory=MemorySpec("2*A + 13", ("*DELAY_INIT(A + 2)",),
                                "DELAY(TIME, B, C, C, 1.0, Z, OFFSET, A + 2)",
                                ("*DELAY_STORE(TIME, B / A, B, C, Z, OFFSET, A + 2)",),
                                samples=rt.DELAY_NEXT, horizon="B", clock=rt.delay_clock,
                                knots=rt.delay_knots),
              variants=(
                  # ACSL: IC until TIME - TDL reaches t0, then X(t - TDL(t)) from NMX
                  # points at least DMIN apart (and TDL/NMX: they span the delay);
                  # TDL may change in time. The surface TIME - TDL - t0 makes the run
                  # restart where the value jumps from IC to X(t0) (a breakpoint
                  # when TDL is constant).
                  Func("DELAY", Kind.MEMORY, "DELAY(X, IC, TDL, NMX[, DMIN])",
                       "IC for t - TDL < t0, else X(t - TDL) from NMX points at least DMIN "
                       "apart, interpolated",
                       literal_args=(3,), positive_args=(2,), surfaces=("TIME - C - START",),
                       memory=MemorySpec(
                           "2*D + 13", ("*DELAY_INIT(D + 2)",),
                           "(DELAY(TIME, C, A, B, 0.0, Z, OFFSET, D + 2) if M0 >= 0 else B)",
                           ("*DELAY_STORE(TIME, AMAX1(E, C / D), C, A, Z, OFFSET, D + 2)",),
                           samples=rt.DELAY_NEXT, horizon="C", clock=rt.delay_clock,
                           knots=rt.delay_knots)),
              )))

# --- random: one stream per call site, a draw held for an output interval --------
# (DELT with a fixed step); the slots are runtime.draw's. CSMP's forms take the
# stream's own seed as first argument.
_DRAWN = ("0.0", "-INF", "-1.0", "0.0")


def _random(signature: str, doc: str, draw: str, **kw: Any) -> Func:
    return Func(signature[:signature.index("(")], Kind.MEMORY, signature, doc,
                memory=MemorySpec("4", _DRAWN, "Z0", (f"*DRAW({draw})",), every_step=False,
                                  wakes=1), **kw)


_RUN = "TIME, HOLD, SEED, SITE"
register(replace(
    _random("GAUSS(M, S)", "normal, mean M and standard deviation S",
            f"0.0, {_RUN}, 0.0, Z, OFFSET, A, B, 0.0"),
    variants=(_random("GAUSS(SEED, M, S)", "CSMP: normal, mean M, standard deviation S, "
                      "from the stream seeded by SEED", f"0.0, {_RUN}, A, Z, OFFSET, B, C, 0.0",
                      constant_args=(0,)),)))
register(_random("UNIF(A, B)", "uniform on [A, B)", f"1.0, {_RUN}, 0.0, Z, OFFSET, A, B, 0.0"))
register(_random("RNDGEN(SEED)", "CSMP: uniform on [0, 1) from the stream seeded by SEED",
                 f"1.0, {_RUN}, A, Z, OFFSET, 0.0, 1.0, 0.0", constant_args=(0,)))
register(_random("OU(TC, M, S)", "Ornstein-Uhlenbeck process with time constant TC, mean M "
                 "and standard deviation S, from y(t0) = M",
                 f"2.0, {_RUN}, 0.0, Z, OFFSET, A, B, C", constant_args=(0,),
                 positive_args=(0,)))

# --- tables ----------------------------------------------------------------------
register(Func("AFGEN", Kind.TABLE, "AFGEN(F, X)", "linear interpolation in a FUNCTION table",
              lookup="AFGEN"))
register(Func("NLFGEN", Kind.TABLE, "NLFGEN(F, X)",
              "quadratic interpolation in a FUNCTION table", lookup="NLFGEN"))
# FST's weather names (section 13) read the day's value, floor(TIME), from a table per
# name that a run fills from the CABO files (`run.prepare`): WEATHER_TABLE + name (in
# lower case: no listing can name it). The value is held in memory, read again where
# the run restarts (every day's start is a breakpoint): within a day's segment every
# stage of a step sees that day, the stage at the segment's end included. Neither is
# callable from a listing.
WEATHER_FUNC, WEATHER_LOOKUP, WEATHER_TABLE = ".WEATHER", "WDAY", "wx_"
WEATHER_HOLD = ".WEATHER_HOLD"
register(Func(WEATHER_FUNC, Kind.TABLE, ".WEATHER(F, X)", "the day's weather value",
              lookup=WEATHER_LOOKUP))
# CSMP III's IMPL (section 13) starts each solve from the last accepted value of its
# unknown (IC at first): that value is kept here. Not callable from a listing.
IMPL_LAST = ".IMPL_LAST"
register(Func(IMPL_LAST, Kind.MEMORY, ".IMPL_LAST(IC, Y)", "Y at the last accepted step",
              memory=MemorySpec("1", ("A",), "Z0", ("B",)), constant_args=(0,)))
# A Fortran routine after STOP that changes a variable it is given (FST's generated code
# keeps every variable from one rate calculation to the next) reads the value the
# routine left at the last step point (IC before the first): Z1 that value, Z0 the one
# before it and Z2 the point where Z1 was taken, so that the rates taken again at that
# point read what they read the first time (Z0): one change per step point, as FSE's
# Euler loop makes it. Not callable from a listing; .BEFORE(X) is X's value before the
# CALL: the day's for a weather name, else .KEPT(0, X) (check/lower.py).
KEPT, BEFORE = ".KEPT", ".BEFORE"
_KEPT_VALUE = "(Z0 if TIME == Z2 else Z1)"
register(Func(KEPT, Kind.MEMORY, ".KEPT(IC, X)", "X as the routine left it at the last step",
              memory=MemorySpec("3", ("A", "A", "-INF"), _KEPT_VALUE, ("VALUE", "B", "TIME"),
                                delayed=True),
              constant_args=(0,)))
register(Func(BEFORE, Kind.MEMORY, ".BEFORE(X)", "X before a routine's CALL changes it",
              memory=MemorySpec("3", ("0.0", "0.0", "-INF"), _KEPT_VALUE,
                                ("VALUE", "A", "TIME"), delayed=True)))
register(Func(WEATHER_HOLD, Kind.MEMORY, ".WEATHER_HOLD(X)", "X as at the last restart",
              memory=MemorySpec("1", ("0.0",), "Z0", ("A",), every_step=False)))
register(Func("LINT", Kind.TABLE, "LINT(F, X)",
              "linear interpolation in a FUNCTION table; outside it the end segments are "
              "extended, with a warning", lookup="LINT", extends=True))
# FST's LINT2('F', F, N, X): the reader checks the name and drops it; N (the table's
# length in FST's arrays) is read and not needed
register(Func("LINT2", Kind.TABLE, "LINT2(F, N, X)",
              "LINT with FST's arguments: LINT2('F', F, N, X)", lookup="LINT", extends=True,
              table_at=0, x_at=2))
