"""Switching surfaces, analysed: the one place that knows how a surface's sign
selects a branch and what a surface expression depends on.

- `sign`, `level`: a surface's mode from its value (a sign, or QNTZR's level);
- `constant_value`: the value of an expression of numbers and constants;
- `linear_gradient`: d e / d y for a surface linear in the states (exact rates);
- `is_affine`: whether a surface on TIME alone is affine in it (its root is then
  a breakpoint, found exactly before the run).

Pure functions over IR expressions; stdlib only (the checker imports this).
"""

from __future__ import annotations

import math

from . import syntax as syn


def sign(x: float) -> float:
    """The mode of a sign surface: -1, 0 or +1."""
    return 1.0 if x > 0 else (-1.0 if x < 0 else 0.0)


def level(v: float) -> float:
    """QNTZR's level k, with (k - 1/2) < v <= (k + 1/2) (round half down)."""
    return float(math.ceil(v - 0.5))


def constant_value(expr, constants: dict[str, float]) -> float | None:
    """The value of an expression of numbers and known constants, else None."""
    if isinstance(expr, syn.Num):
        return expr.value
    if isinstance(expr, syn.Name):
        return constants.get(expr.name)
    if isinstance(expr, syn.Neg):
        v = constant_value(expr.operand, constants)
        return None if v is None else -v
    if isinstance(expr, syn.BinOp):
        a, b = constant_value(expr.left, constants), constant_value(expr.right, constants)
        if a is None or b is None:
            return None
        try:
            if expr.op == "/":
                return a / b
            return {"+": a + b, "-": a - b, "*": a * b}.get(expr.op)
        except ZeroDivisionError:
            return None
    return None


def linear_gradient(expr, state_index: dict[str, int],
                    constants: dict[str, float]) -> list[float] | None:
    """d e/d y for a surface that is a constant-coefficient combination of states
    (None otherwise, or when it reads no state at all)."""
    n = len(state_index)

    def lin(e) -> tuple[list[float], bool] | None:  # (gradient, is constant)
        if isinstance(e, syn.Num):
            return [0.0] * n, True
        if isinstance(e, syn.Name):
            if e.name in state_index:
                g = [0.0] * n
                g[state_index[e.name]] = 1.0
                return g, False
            if e.name in constants:
                return [0.0] * n, True
            return None
        if isinstance(e, syn.Neg):
            r = lin(e.operand)
            return None if r is None else ([-v for v in r[0]], r[1])
        if isinstance(e, syn.BinOp):
            a, b = lin(e.left), lin(e.right)
            if a is None or b is None:
                return None
            if e.op in "+-":
                s = 1.0 if e.op == "+" else -1.0
                return [p + s * q for p, q in zip(a[0], b[0], strict=True)], a[1] and b[1]
            if e.op == "*" and (a[1] or b[1]):
                k = constant_value(e.left if a[1] else e.right, constants)
                if k is None:
                    return None
                return [k * v for v in (b[0] if a[1] else a[0])], a[1] and b[1]
            if e.op == "/" and b[1]:
                k = constant_value(e.right, constants)
                if k is None or k == 0:
                    return None
                return [v / k for v in a[0]], a[1]
            return None
        return None

    r = lin(expr)
    if r is None or r[1]:
        return None
    return r[0]


def is_affine(expr, constants: dict[str, float], equations: dict | None = None) -> bool:
    """True if a time-only surface is affine in TIME (its root is then exact),
    looking through the algebraic variables it reads."""
    equations = equations or {}
    memo: dict[str, int] = {}

    def lin(e) -> int:  # 0 constant, 1 affine, 2 other
        if isinstance(e, syn.Num):
            return 0
        if isinstance(e, syn.Name):
            if e.name == "TIME":
                return 1
            if e.name in constants:
                return 0
            if e.name in equations:
                if e.name not in memo:
                    memo[e.name] = 2  # a cycle never reaches here; be safe anyway
                    memo[e.name] = lin(equations[e.name])
                return memo[e.name]
            return 2
        if isinstance(e, syn.Neg):
            return lin(e.operand)
        if isinstance(e, syn.BinOp):
            a, b = lin(e.left), lin(e.right)
            if e.op in "+-":
                return max(a, b)
            if e.op == "*":
                return a + b if a + b <= 1 else 2
            if e.op == "/":
                return a if b == 0 else 2
            return 0 if a == b == 0 else 2
        if isinstance(e, syn.Call):
            return 0 if all(lin(x) == 0 for x in e.args) else 2
        return 2
    return lin(expr) <= 1
