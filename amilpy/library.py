"""The functions a listing may call: their arity, kind, value and switching surfaces.

Kinds (the contract's section 5):
  math    a plain function of its arguments (ABS, SIN, AMAX1, ...)
  state   introduces states (INTGRL, REALPL, LEDLAG, CMPXPL, MODINT)
  switch  a branch selected by the sign of one or more surfaces (FSW, LIMIT, ...)
  time    a switch whose surface is TIME minus a constant (STEP, RAMP, SINE)
  memory  keeps a value from the last accepted step (HSTRSS, ZHOLD, RST, PULSE, DERIV)
  impulse IMPULS: 1 at t = P1 + k*P2, else 0
  table   AFGEN / NLFGEN interpolation in a FUNCTION table

Switch values are written as small Python templates over their arguments (`A`,
`B`, ...) and the frozen modes of their surfaces (`M0`, `M1`, ...). A template is
compiler text, parsed once; the compiler substitutes syntax trees built from the
model for the placeholders, so no model text is ever pasted into source.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Func:
    name: str
    kind: str
    nargs: tuple[int, int | None]  # min, max (None: any number >= min)
    # For switches: one template per output, and the surfaces as templates over
    # the arguments; "level" marks a QNTZR surface.
    values: tuple[str, ...] = ()
    surfaces: tuple[str, ...] = ()
    surface_kind: str = "sign"
    outputs: int = 1
    doc: str = ""


def _f(name, kind, nargs, values=(), surfaces=(), **kw) -> Func:
    return Func(name, kind, nargs, tuple(values), tuple(surfaces), **kw)


FUNCTIONS: dict[str, Func] = {}
ALIASES: dict[str, str] = {}


def _register(func: Func, *aliases: str) -> None:
    FUNCTIONS[func.name] = func
    for alias in aliases:
        ALIASES[alias] = func.name


# --- mathematical (Fortran meanings) -----------------------------------------
for _name in ("ABS", "SQRT", "EXP", "ALOG", "ALOG10", "SIN", "COS", "TAN", "ASIN", "ACOS",
              "ATAN", "SINH", "COSH", "TANH", "AINT", "FLOAT"):
    _register(_f(_name, "math", (1, 1)))
ALIASES.update({"LOG": "ALOG", "LOG10": "ALOG10", "INT": "AINT"})
for _name in ("ATAN2", "AMOD", "SIGN"):
    _register(_f(_name, "math", (2, 2)))
ALIASES["MOD"] = "AMOD"
_register(_f("AMAX1", "math", (2, None)), "MAX", "AMAX0", "MAX1")
_register(_f("AMIN1", "math", (2, None)), "MIN", "AMIN0", "MIN1")

# --- states -------------------------------------------------------------------
_register(_f("INTGRL", "state", (2, 2), doc="Y = IC + integral of X"))
_register(_f("INTEG", "state", (2, 2), doc="ACSL order: INTEG(X, IC)"))
_register(_f("REALPL", "state", (3, 3), doc="P*Y' + Y = X, Y(0) = IC"))
_register(_f("LEDLAG", "state", (3, 3), doc="(P1*s + 1)/(P2*s + 1) applied to X"))
_register(_f("CMPXPL", "state", (5, 5), doc="Y'' + 2*P1*P2*Y' + P2**2*Y = X"))
_register(_f("MODINT", "state", (4, 4), surfaces=("B", "C"),
             doc="X1>0: integrate X3; else X2>0: reset to IC; else hold"))

# --- switches -----------------------------------------------------------------
_register(_f("FCNSW", "switch", (4, 4),
             values=("(B if M0 < 0 else (D if M0 > 0 else C))",), surfaces=("A",),
             doc="A if X<0; B if X=0; C if X>0"), "FSW")
_register(_f("INSW", "switch", (3, 3), values=("(B if M0 < 0 else C)",), surfaces=("A",),
             doc="A if X<0; B if X>=0"))
_register(_f("OUTSW", "switch", (2, 2), values=("(B if M0 < 0 else 0.0)", "(0.0 if M0 < 0 else B)"),
             surfaces=("A",), outputs=2, doc="X<0: (V, 0); X>=0: (0, V)"))
_register(_f("COMPAR", "switch", (2, 2), values=("(0.0 if M0 < 0 else 1.0)",),
             surfaces=("A - B",), doc="0 if X1<X2; 1 if X1>=X2"))
_register(_f("LIMIT", "switch", (3, 3), values=("(A if M0 < 0 else (B if M1 > 0 else C))",),
             surfaces=("C - A", "C - B"), doc="min(P2, max(P1, X))"), "BOUND")
_register(_f("DEADSP", "switch", (3, 3),
             values=("((C - B) if M1 > 0 else ((C - A) if M0 < 0 else 0.0))",),
             surfaces=("C - A", "C - B"), doc="0 if P1<=X<=P2; X-P2 above; X-P1 below"), "DEAD")
_register(_f("QNTZR", "switch", (2, 2), values=("(M0 * A)",), surfaces=("B / A",),
             surface_kind="level", doc="P*k for (k-1/2)P < X <= (k+1/2)P"))
for _name, _value in (
    ("AND", "(1.0 if (M0 > 0 and M1 > 0) else 0.0)"),
    ("IOR", "(1.0 if (M0 > 0 or M1 > 0) else 0.0)"),
    ("NOR", "(0.0 if (M0 > 0 or M1 > 0) else 1.0)"),
    ("NAND", "(0.0 if (M0 > 0 and M1 > 0) else 1.0)"),
    ("EOR", "(1.0 if ((M0 > 0) != (M1 > 0)) else 0.0)"),
    ("EQUIV", "(1.0 if ((M0 > 0) == (M1 > 0)) else 0.0)"),
):
    _register(_f(_name, "switch", (2, 2), values=(_value,), surfaces=("A", "B")))
_register(_f("NOT", "switch", (1, 1), values=("(0.0 if M0 > 0 else 1.0)",), surfaces=("A",)))

# --- time switches (surface TIME - P: breakpoints known before the run) --------
_register(_f("STEP", "time", (1, 1), values=("(0.0 if M0 < 0 else 1.0)",),
             surfaces=("TIME - A",), doc="0 for t<P; 1 for t>=P"))
_register(_f("RAMP", "time", (1, 1), values=("(0.0 if M0 < 0 else TIME - A)",),
             surfaces=("TIME - A",), doc="0 for t<P; t-P after"))
_register(_f("SINE", "time", (3, 3), values=("(0.0 if M0 < 0 else SIN(B*(TIME - A) + C))",),
             surfaces=("TIME - A",), doc="0 for t<P1; sin(P2(t-P1)+P3) after"))
_register(_f("IMPULS", "impulse", (2, 2), doc="1 at t = P1 + k*P2"))

# --- memory (updated only on accepted steps) ------------------------------------
_register(_f("HSTRSS", "memory", (4, 4), doc="Y = min(X-P1, max(X-P2, prev)), Y(0)=IC"))
_register(_f("ZHOLD", "memory", (2, 2), surfaces=("A",), doc="X2 while X1>0 else prev"))
_register(_f("RST", "memory", (3, 3), surfaces=("A", "B", "C"), doc="reset-set flip-flop"))
_register(_f("PULSE", "memory", (2, 2), surfaces=("B",), doc="Y=1 for at least P from X>0"))
_register(_f("DERIV", "memory", (2, 2), doc="dX/dt, Y(0)=IC"))

# --- tables ----------------------------------------------------------------------
_register(_f("AFGEN", "table", (2, 2), doc="linear interpolation in a FUNCTION table"))
_register(_f("NLFGEN", "table", (2, 2), doc="quadratic interpolation in a FUNCTION table"))

MEMORY_SLOTS = {"HSTRSS": 1, "ZHOLD": 1, "RST": 1, "PULSE": 1, "DERIV": 5}


def lookup(name: str) -> Func | None:
    return FUNCTIONS.get(ALIASES.get(name, name))


# ------------------------------------------------------------ run-time helpers
# These are the only callables generated code can reach (see codegen.NAMESPACE).


def fortran_sign(a: float, b: float) -> float:
    return abs(a) if b >= 0.0 else -abs(a)


def fortran_aint(x: float) -> float:
    return float(math.trunc(x))


def fortran_amod(a: float, b: float) -> float:
    """Fortran MOD: the remainder with the sign of a (NaN for b = 0)."""
    try:
        return math.fmod(a, b)
    except ValueError:
        return math.nan


def safe_exp(x: float) -> float:
    try:
        return math.exp(x)
    except OverflowError:
        return math.inf


def safe_pow(a: float, b: float) -> float:
    try:
        r = a**b
    except OverflowError:
        return math.inf
    except ZeroDivisionError:
        return math.inf
    if isinstance(r, complex):
        return math.nan
    return r


def safe_div(a: float, b: float) -> float:
    try:
        return a / b
    except ZeroDivisionError:
        if a == 0.0 or a != a:
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)


def safe_sqrt(x: float) -> float:
    return math.sqrt(x) if x >= 0.0 else math.nan


def safe_log(x: float) -> float:
    if x > 0.0:
        return math.log(x)
    return -math.inf if x == 0.0 else math.nan


def safe_log10(x: float) -> float:
    if x > 0.0:
        return math.log10(x)
    return -math.inf if x == 0.0 else math.nan


def _domain(f):
    def g(x: float) -> float:
        try:
            return f(x)
        except (ValueError, OverflowError):
            return math.nan

    g.__name__ = f.__name__
    return g


def afgen(table: tuple[tuple[float, ...], tuple[float, ...]], x: float) -> float:
    """Linear interpolation; the end values hold outside the table."""
    xs, ys = table
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    i = bisect.bisect_right(xs, x) - 1
    x0, x1 = xs[i], xs[i + 1]
    return ys[i] + (ys[i + 1] - ys[i]) * (x - x0) / (x1 - x0)


def nlfgen(table: tuple[tuple[float, ...], tuple[float, ...]], x: float) -> float:
    """Three-point Lagrange interpolation; the end values hold outside the table."""
    xs, ys = table
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    n = len(xs)
    if n < 3:
        return afgen(table, x)
    i = bisect.bisect_right(xs, x) - 1
    # the three points nearest x: i-1, i, i+1 (shifted inside the table)
    j = min(max(i - 1 if (x - xs[i]) < (xs[i + 1] - x) else i, 0), n - 3)
    x0, x1, x2 = xs[j], xs[j + 1], xs[j + 2]
    y0, y1, y2 = ys[j], ys[j + 1], ys[j + 2]
    return (y0 * (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2))
            + y1 * (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2))
            + y2 * (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1)))


def deriv(x: float, t: float, x1: float, t1: float, x2: float, t2: float,
          previous: float) -> float:
    """DERIV: dX/dt from the last two accepted points and the current one.

    Second order (exact for a quadratic in time) once two earlier points are
    known; a plain difference after a start; the last value at a step end.
    """
    if not t > t1:
        return previous
    if t2 < t1:
        return (x2 * (t - t1) / ((t2 - t1) * (t2 - t))
                + x1 * (t - t2) / ((t1 - t2) * (t1 - t))
                + x * ((t - t2) + (t - t1)) / ((t - t2) * (t - t1)))
    return (x - x1) / (t - t1)


def impulse_at(t: float, start: float, period: float) -> float:
    """1.0 when t is (to rounding) one of start + k*period, k >= 0; else 0.0."""
    if t < start - 1e-12 * max(1.0, abs(start)):
        return 0.0
    if period <= 0.0:
        return 1.0 if abs(t - start) <= 1e-12 * max(1.0, abs(t)) else 0.0
    k = round((t - start) / period)
    return 1.0 if abs(start + k * period - t) <= 1e-9 * max(period, abs(t) * 1e-3) else 0.0


MATH: dict[str, object] = {
    "ABS": abs,
    "SQRT": safe_sqrt,
    "EXP": safe_exp,
    "ALOG": safe_log,
    "ALOG10": safe_log10,
    # raw math functions: a domain fault (SIN of an infinity, ASIN(2)) raises
    # ValueError, which the runner turns into a rejected step or a failure with
    # the line, and the constant evaluator into an error at the listing's line
    "SIN": math.sin,
    "COS": math.cos,
    "TAN": math.tan,
    "ASIN": math.asin,
    "ACOS": math.acos,
    "ATAN": math.atan,
    "SINH": _domain(math.sinh),
    "COSH": _domain(math.cosh),
    "TANH": math.tanh,
    "AINT": fortran_aint,
    "FLOAT": float,
    "ATAN2": math.atan2,
    "AMOD": fortran_amod,
    "SIGN": fortran_sign,
    "AMAX1": max,
    "AMIN1": min,
}


def vector_functions() -> dict[str, object]:
    """The same functions on NumPy arrays, elementwise: the runner evaluates the
    generated surface and output functions over a whole chunk of output instants
    at once (the same code object, run with these in its namespace)."""
    import functools

    import numpy as np

    def sign(a, b):
        return np.where(np.asarray(b) >= 0.0, np.abs(a), -np.abs(a))

    def many(f):
        return lambda *args: functools.reduce(f, args)

    def each(f):
        return np.vectorize(f, otypes=[float])

    return {
        "ABS": np.abs, "SQRT": np.sqrt, "EXP": np.exp, "ALOG": np.log, "ALOG10": np.log10,
        "SIN": np.sin, "COS": np.cos, "TAN": np.tan, "ASIN": np.arcsin, "ACOS": np.arccos,
        "ATAN": np.arctan, "SINH": np.sinh, "COSH": np.cosh, "TANH": np.tanh,
        "AINT": np.trunc, "FLOAT": lambda x: np.asarray(x, dtype=float),
        "ATAN2": np.arctan2, "AMOD": np.fmod, "SIGN": sign,
        "AMAX1": many(np.maximum), "AMIN1": many(np.minimum),
        "AFGEN": lambda table, x: np.interp(x, table[0], table[1]),
        "NLFGEN": lambda table, x: each(lambda v: nlfgen(table, v))(x),
        "DERIV": each(deriv), "IMPULS": each(impulse_at), "POW": np.power,
        "LEVEL": lambda v: np.ceil(np.asarray(v) - 0.5), "SGN": np.sign,
        "WHERE": np.where, "ALL": many(np.logical_and), "ANY": many(np.logical_or),
    }
