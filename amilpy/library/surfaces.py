"""Switching surfaces, analysed: the one place that knows how a surface's sign
selects a branch and what a surface expression depends on.

- `sign`, `level`: a surface's mode from its value (a sign, or QNTZR's level);
- `constant_value`: the value of an expression of numbers and constants;
- `linear_gradient`: d e / d y for a surface linear in the states (exact rates);
- `is_affine`: whether a surface on TIME alone is affine in it (its root is then
  a breakpoint, found exactly before the run).

Pure functions over IR expressions, each a complete visitor of `ir.EXPRESSIONS`
(a new node must say what it means here); stdlib only (the checker imports this).
"""

from __future__ import annotations

import math
from dataclasses import replace

from .. import ir
from ..parse import syntax as syn
from ..parse.syntax import Visitor, deep_enough


def sign(x: float) -> float:
    """The mode of a sign surface: -1, 0 or +1."""
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


def amod_at(a: float, b: float, m: float) -> float:
    """AMOD(A, B) in the branch in force, A - B*AINT(A/B) with AINT(|A/B|) held at
    -m (the mode of its level surface): fmod's exact remainder where it is that
    branch's value (A - k*B rounds to nothing when A is large: AMOD(1E20, 7) is 2,
    not 0), the branch continued past its edge until the crossing is located."""
    branch = a + m * (1.0 if a > 0 else (-1.0 if a < 0 else 0.0)) * abs(b)
    if b != 0.0:
        # (math.fmod, which numba has not: % of positive floats is exact too) -- where
        # it is the branch's value: A/B may round onto a whole number the exact
        # quotient is just below (AMOD(0.5, 0.1): the branch says 0, fmod 0.1)
        exact = math.copysign(abs(a) % abs(b), a)
        if abs(exact - branch) <= 0.5 * abs(b):
            return exact
    return branch


# How the motion leaves a switching surface it stands on, from the surface's rate
# of change under its + branch (dp) and under its - branch (dm): the one rule, read
# by the run loop (run/watch.py) and compiled into the numba kernel
# (compiled/kernel.py), which leaves to the loop what it cannot decide alone.
UP, DOWN = 1.0, -1.0  # both branches carry the motion to that side
STILL = 0.0  # neither branch moves the surface (both rates negligible)
SLIDES = 2.0  # both branches carry it back onto the surface: it slides along it
REPELS = 3.0  # both carry it away: it keeps going the way it was going
UNCLEAR = 4.0  # a rate within its noise: the motion stays on the surface
STILL_RATE = 1e-13  # a rate below this fraction of the larger one is negligible
RATE_NOISE = 1e-9  # relative noise of a rate computed by differences


def leaving(dp: float, dm: float, exact: bool) -> float:
    """UP, DOWN, STILL, SLIDES, REPELS or UNCLEAR for rates `dp`, `dm` (`exact`:
    from the surface's gradient, with no difference noise). Plain float arithmetic
    (numba compiles it as it is)."""
    scale = max(abs(dp), abs(dm))
    if not scale > 1e-300 or (abs(dp) <= STILL_RATE * scale
                              and abs(dm) <= STILL_RATE * scale):
        return STILL
    eps = 0.0 if exact else RATE_NOISE * scale
    up, down = dp > eps, dm < -eps
    if up and down:
        return REPELS
    if up:
        return UP
    if down:
        return DOWN
    if dp < -eps and dm > eps:
        return SLIDES
    return UNCLEAR


def level(v: float) -> float:
    """QNTZR's level k, with (k - 1/2) < v <= (k + 1/2) (round half down), exactly:
    v - 1/2 rounds (-0.49999999999999994 - 0.5 is -1.0), so the band is checked."""
    # (in floats: numba compiles this as written, and an integer would wrap past
    # 2**63; ceil(a) = -floor(-a), + 0.0 for no -0.0)
    if v != v:
        raise ValueError("the level of NaN")
    if v - v != 0.0:
        raise OverflowError("the level of an infinity")
    k = -((0.5 - v) // 1.0) + 0.0
    if v <= k - 0.5:
        k -= 1.0
    elif v > k + 0.5:
        k += 1.0
    return k


def slides(mode: float) -> bool:
    """Whether a surface in this mode slides: a mode half a whole number (a sign
    surface's `run.plan.SLIDE`, a level surface's edge between two levels)."""
    return mode % 1.0 == 0.5


def level_edge(v: float, k: float) -> float:
    """A level surface's value in mode k. In level k (a whole number): how far v is
    inside its band (k - 1/2, k + 1/2], the nearer edge's distance, negative once v has
    left it. Sliding on the edge k (`slides`): v - k, negative below the edge, as a
    sign surface's value."""
    if slides(k):
        return v - k
    return 0.5 - abs(v - k)


def truth(x: float) -> bool:
    """A number used as a condition: true iff > 0 (TERMT, IF, the logic functions)."""
    return x > 0.0


def operate(op: str, a: float, b: float) -> float | None:
    """a op b for the arithmetic, relational and logical operators of the language
    (None for a division by zero, and for ** which the compiler folds itself)."""
    try:
        if op == "/":
            return a / b
        value = {"+": lambda: a + b, "-": lambda: a - b, "*": lambda: a * b,
                 "<": lambda: a < b, "<=": lambda: a <= b, ">": lambda: a > b,
                 ">=": lambda: a >= b, "==": lambda: a == b, "/=": lambda: a != b,
                 "AND": lambda: truth(a) and truth(b), "OR": lambda: truth(a) or truth(b),
                 "EQV": lambda: truth(a) == truth(b), "NEQV": lambda: truth(a) != truth(b),
                 }.get(op)
        return None if value is None else float(value())
    except ZeroDivisionError:
        return None


class _Constant(Visitor):
    """The value of an expression of numbers and known constants, else None."""

    complete = ir.EXPRESSIONS

    def __init__(self, constants: dict[str, float]) -> None:
        self.constants = constants

    def visit_Num(self, e: syn.Num) -> float | None:
        return e.value

    def visit_Name(self, e: syn.Name) -> float | None:
        return self.constants.get(e.name)

    def visit_Neg(self, e: syn.Neg) -> float | None:
        v = self.visit(e.operand)
        return None if v is None else -v

    def visit_BinOp(self, e: syn.BinOp) -> float | None:
        a, b = self.visit(e.left), self.visit(e.right)
        return None if a is None or b is None else operate(e.op, a, b)

    def visit_Not(self, e: syn.Not) -> float | None:
        v = self.visit(e.operand)
        return None if v is None else float(not truth(v))

    def _unknown(self, e) -> None:
        # a function, a switch, a memory or a table: not folded here (the
        # compiler's constant evaluator handles what is constant among them)
        return None

    visit_Call = visit_SwitchValue = visit_MemoryValue = _unknown
    visit_TableLookup = visit_Impulse = visit_UnitValue = _unknown


@deep_enough()
def constant_value(expr: syn.Node, constants: dict[str, float]) -> float | None:
    """The value of an expression of numbers and known constants, else None."""
    return _Constant(constants).visit(expr)


class _Linear(Visitor):
    """(gradient, is constant) of an expression linear in the states, else None."""

    complete = ir.EXPRESSIONS

    def __init__(self, state_index: dict[str, int], constants: dict[str, float]) -> None:
        self.state_index = state_index
        self.constants = constants
        self.n = len(state_index)

    def visit_Num(self, e):
        return [0.0] * self.n, True

    def visit_Name(self, e):
        if e.name in self.state_index:
            g = [0.0] * self.n
            g[self.state_index[e.name]] = 1.0
            return g, False
        if e.name in self.constants:
            return [0.0] * self.n, True
        return None  # TIME or an algebraic variable

    def visit_Neg(self, e):
        r = self.visit(e.operand)
        return None if r is None else ([-v for v in r[0]], r[1])

    def visit_BinOp(self, e):
        a, b = self.visit(e.left), self.visit(e.right)
        if a is None or b is None or e.op not in ("+", "-", "*", "/"):
            return None
        if e.op in "+-":
            s = 1.0 if e.op == "+" else -1.0
            return [p + s * q for p, q in zip(a[0], b[0], strict=True)], a[1] and b[1]
        if e.op == "*" and (a[1] or b[1]):
            k = constant_value(e.left if a[1] else e.right, self.constants)
            if k is None:
                return None
            return [k * v for v in (b[0] if a[1] else a[0])], a[1] and b[1]
        if e.op == "/" and b[1]:
            k = constant_value(e.right, self.constants)
            if k is None or k == 0:
                return None
            return [v / k for v in a[0]], a[1]
        return None

    def _nonlinear(self, e) -> None:
        return None  # a function of the states: no exact gradient

    visit_Call = visit_SwitchValue = visit_MemoryValue = _nonlinear
    visit_TableLookup = visit_Impulse = visit_Not = visit_UnitValue = _nonlinear


@deep_enough()
def linear_gradient(expr: syn.Node, state_index: dict[str, int],
                    constants: dict[str, float]) -> list[float] | None:
    """d e/d y for a surface that is a constant-coefficient combination of states
    (None otherwise, or when it reads no state at all)."""
    r = _Linear(state_index, constants).visit(expr)
    if r is None or r[1]:
        return None
    return r[0]


CONSTANT, AFFINE, OTHER = 0, 1, 2


class _Affine(Visitor):
    """CONSTANT, AFFINE or OTHER in TIME, looking through algebraic variables."""

    complete = ir.EXPRESSIONS

    def __init__(self, constants: dict[str, float], equations: dict) -> None:
        self.constants = constants
        self.equations = equations
        self.memo: dict[str, int] = {}

    def visit_Num(self, e) -> int:
        return CONSTANT

    def visit_Name(self, e) -> int:
        if e.name == "TIME":
            return AFFINE
        if e.name in self.constants:
            return CONSTANT
        if e.name not in self.equations:
            return OTHER
        if e.name not in self.memo:
            self.memo[e.name] = OTHER  # a cycle never reaches here; be safe anyway
            self.memo[e.name] = self.visit(self.equations[e.name])
        return self.memo[e.name]

    def visit_Neg(self, e) -> int:
        return self.visit(e.operand)

    def visit_BinOp(self, e) -> int:
        a, b = self.visit(e.left), self.visit(e.right)
        if e.op not in ("+", "-", "*", "/", "**"):  # a truth: it jumps
            return CONSTANT if a == b == CONSTANT else OTHER
        if e.op in "+-":
            return max(a, b)
        if e.op == "*":
            return a + b if a + b <= AFFINE else OTHER
        if e.op == "/":
            return a if b == CONSTANT else OTHER
        return CONSTANT if a == b == CONSTANT else OTHER  # **

    def visit_Call(self, e) -> int:
        return CONSTANT if all(self.visit(x) == CONSTANT for x in e.args) else OTHER

    def visit_Not(self, e) -> int:
        return CONSTANT if self.visit(e.operand) == CONSTANT else OTHER

    def _other(self, e) -> int:
        # a switch's value jumps, a memory's moves with the states, a table
        # is not affine, IMPULS is a train of instants, a unit's output may jump
        return OTHER

    visit_SwitchValue = visit_MemoryValue = visit_TableLookup = visit_Impulse = _other
    visit_UnitValue = _other


@deep_enough()
def is_affine(expr: syn.Node, constants: dict[str, float], equations: dict | None = None
              ) -> bool:
    """True if a time-only surface is affine in TIME (its root is then exact),
    looking through the algebraic variables it reads."""
    return _Affine(constants, equations or {}).visit(expr) <= AFFINE


_RANK = {ir.Depends.CONST: 0, ir.Depends.TIME: 1, ir.Depends.STATE: 2}


class _Dependence(Visitor):
    """What an IR expression's value moves with: CONST, TIME or STATE (memoised per
    variable and per switch, so a switch nested N deep is classified in O(N))."""

    complete = ir.EXPRESSIONS

    def __init__(self, model: ir.Model) -> None:
        self.model = model
        self.states = {s.name for s in model.states}
        # names code run at instants keeps (ACSL's written-order code, FST's SET
        # variables) change at events: like states, a surface on them is watched (its
        # branch is chosen again at each restart)
        self.states |= set(model.kept)
        self.equations = {e.target: e.expr for e in model.dynamic}
        self.names: dict[str, ir.Depends] = {}
        self.switches: dict[int, ir.Depends] = {}

    def most(self, exprs) -> ir.Depends:
        best = ir.Depends.CONST
        for e in exprs:
            d = self.visit(e)
            if _RANK[d] > _RANK[best]:
                best = d
                if best is ir.Depends.STATE:
                    break
        return best

    def visit_Num(self, e) -> ir.Depends:
        return ir.Depends.CONST

    def visit_Name(self, e) -> ir.Depends:
        if e.name == "TIME":
            return ir.Depends.TIME
        if e.name in self.states:
            return ir.Depends.STATE
        if e.name not in self.equations:
            return ir.Depends.CONST
        if e.name not in self.names:
            self.names[e.name] = ir.Depends.STATE  # guards recursion on malformed input
            self.names[e.name] = self.visit(self.equations[e.name])
        return self.names[e.name]

    def visit_Neg(self, e) -> ir.Depends:
        return self.visit(e.operand)

    def visit_BinOp(self, e) -> ir.Depends:
        return self.most((e.left, e.right))

    def visit_Not(self, e) -> ir.Depends:
        return self.visit(e.operand)

    def visit_UnitValue(self, e) -> ir.Depends:
        # a unit's outputs move with what it reads (its conditions' surfaces too)
        if ("u", e.unit) not in self.names:
            unit = self.model.units[e.unit]
            self.names[("u", e.unit)] = ir.Depends.STATE
            self.names[("u", e.unit)] = self.most(
                [syn.Name(n, unit.span) for n in unit.inputs]
                + [n for n in walk_code(unit.body) if isinstance(n, ir.SwitchValue)])
        return self.names[("u", e.unit)]

    def visit_Call(self, e) -> ir.Depends:
        return self.most(e.args)

    def visit_TableLookup(self, e) -> ir.Depends:
        return self.visit(e.x)

    def visit_SwitchValue(self, e) -> ir.Depends:
        # a switch's value moves with its arguments and with its branch, which
        # moves with its surfaces (STEP's is TIME - P)
        if e.switch not in self.switches:
            sw = self.model.switches[e.switch]
            self.switches[e.switch] = ir.Depends.STATE
            self.switches[e.switch] = self.most(
                [*sw.args, *(self.model.surfaces[i].expr for i in sw.surfaces)])
        return self.switches[e.switch]

    def visit_MemoryValue(self, e) -> ir.Depends:
        return ir.Depends.STATE

    def visit_Impulse(self, e) -> ir.Depends:
        return ir.Depends.TIME


def walk_code(body) -> list[syn.Node]:
    """Every node of a block of IR statements (their expressions included)."""
    return [n for st in body for n in syn.walk(st)]


@deep_enough()
def classify(model: ir.Model) -> None:
    """Mark each surface of the model const / time / state / impulse by what its
    expression reads (in place: `model.surfaces[i].depends`)."""
    dependence = _Dependence(model)
    for i, s in enumerate(model.surfaces):
        # IMPULS is 1 only at its instants, which are breakpoints: a surface on
        # it never changes sign between steps, so it is not watched
        if any(isinstance(n, ir.Impulse) for n in syn.walk(s.expr)):
            depends = ir.Depends.IMPULSE
        else:
            depends = dependence.visit(s.expr)
        model.surfaces[i] = replace(s, depends=depends)
