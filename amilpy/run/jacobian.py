"""The Jacobian of the vector field, d(dy/dt)/dy, for the analyses: the one place
they take it from (the linear modes, the variational equations of the flow map and
the symmetries of a periodic orbit). `jacobian_at` is the rule, written once:
the model's own (`model_jacobian`, from `codegen.jacobian`: each switch
differentiated in its branch, exact to rounding); where there is none (a sliding
surface's combined field, a construct the symbolic route does not take, a
derivative that faults at the point) central differences of the field,
`field_jacobian`:

Column j is (f(y + h_j e_j) - f(y - h_j e_j)) / (2 h_j) with
h_j = eps**(1/3) * max(|y_j|, floor_j); the caller's floor is the state's size
(along an orbit), at least ABSERR_j / RELERR_j. Truncation, h^2 |f'''| / 6, and
rounding, eps |terms| / h, are then of one size: about eps**(2/3) = 4E-11 of
the entries when the terms that make up a derivative are of the order of the
derivative at the state's scale. A state that is zero where the Jacobian is
taken (a speed at an equilibrium) has no scale of its own, and terms that
cancel (a spring holding a load: C1*X1 - MN) leave rounding of eps*|C1*X1|/h.
`refine=True` (one-off Jacobians: modes, symmetries) therefore tries each
column at h, 4h, ..., 65536h and keeps the largest step whose estimate agrees
with the next smaller step's to 1E-10 of the column (so its truncation error
is below that; where no two agree so well, the pair that agrees best); the
change is its error estimate. A field linear in the states (a frozen switch
branch, springs, dashpots) then comes out exact to rounding at a large step.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .plan import sliding_in

MODEL = "the model's equations"
DIFFERENCES = "central differences"
STEP = float(np.cbrt(np.finfo(float).eps))  # 6.06E-6
REFINE = tuple(4.0 ** k for k in range(9))  # up to 0.4 of the state's size
AGREE = 1e-10


def _column(f, y: list[float], j: int, h: float) -> list[float]:
    up, down = list(y), list(y)
    up[j] += h
    down[j] -= h
    width = up[j] - down[j]
    return [(a - b) / width for a, b in zip(f(up), f(down), strict=True)]


def model_jacobian(c, t: float, y, m, z) -> np.ndarray | None:
    """d rhs/d y of a run's generated model (`codegen.ModelCode`) at (t, y) in the
    branches m, from its equations; None where it cannot be had there."""
    from ..codegen.jacobian import for_compiled

    try:
        jac = for_compiled(c).dense(t, [float(v) for v in y], list(m), list(z))
    except (NotImplementedError, ArithmeticError, ValueError):
        return None
    return jac if np.all(np.isfinite(jac)) else None


def jacobian_at(c, field: Callable[[list[float]], object], t: float, y, m, z, floor,
                refine: bool = False) -> tuple[np.ndarray, np.ndarray, str]:
    """d f/d y at (t, y) in the branches m with memory z: (J, the estimated error of
    each column, how it was had: MODEL or DIFFERENCES). The model's own unless a
    surface slides or it cannot be had (error 0); else central differences of
    `field` (the field at t of a list of the states' values), refined with their
    error estimate when `refine` (one-off Jacobians), plain (error NaN) when not
    (the many along a step of the variational equations)."""
    if not sliding_in(m):
        jac = model_jacobian(c, t, y, m, z)
        if jac is not None:
            return jac, np.zeros(len(jac)), MODEL
    if refine:
        return (*refined(field, y, floor), DIFFERENCES)
    return differences(field, y, floor), np.full(len(y), np.nan), DIFFERENCES


def field_jacobian(f: Callable[[list[float]], object], y, floor,
                   refine: bool = False, with_error: bool = False):
    """d f/d y at y (f: the field at fixed TIME, branches and memory, of a list of
    the states' values); with
    `with_error`, (J, the estimated error of each column) (refined steps)."""
    if refine or with_error:
        jac, error = refined(f, y, floor)
        return (jac, error) if with_error else jac
    return differences(f, y, floor)


def differences(f, y, floor) -> np.ndarray:
    y = [float(v) for v in y]
    h = (STEP * np.maximum(np.abs(y), floor)).tolist()
    if not y:
        return np.empty((0, 0))
    return np.array([_column(f, y, j, h[j]) for j in range(len(y))]).T


def refined(f, y: np.ndarray, floor) -> tuple[np.ndarray, np.ndarray]:
    """(J, estimated error of each column) of f: R^n -> R^m at y: each column at
    the largest step whose estimate agrees with the next smaller one to AGREE of
    the column's size (its truncation error is then below that), else where two
    estimates agree best."""
    y = [float(v) for v in y]
    h = STEP * np.maximum(np.abs(y), floor)
    out = np.empty((len(f(y)) if y else 0, len(y)))  # (f may give other values than y's)
    error = np.zeros(len(y))
    for j in range(len(y)):
        tries = [np.array(_column(f, y, j, k * h[j])) for k in REFINE]
        size = max(float(np.max(np.abs(t))) for t in tries)
        changes = [float(np.max(np.abs(b - a))) for a, b in zip(tries[:-1], tries[1:], strict=True)]
        good = [k for k, c in enumerate(changes) if c <= AGREE * size]
        best = good[-1] if good else int(np.argmin(changes))
        out[:, j] = tries[best]
        error[j] = changes[best]
    return out, error


def branch_difference(f: Callable[[list[float]], object], at: list[float], j: int,
                      h: float) -> np.ndarray:
    """d f / d at[j] (f vector-valued) by a central difference; where f jumps or
    bends within h of the point -- the one-sided differences disagree: a memory
    update that reads the sign of a trigger standing at zero, as it does where it
    was just crossed -- by the second-order one-sided difference on the side where
    f is straighter, the branch the point itself is on (exact for a piecewise
    linear f, O(h^2) for a smooth one whose curvature alone parted the sides). A
    component that is not finite at the point has no derivative: 0."""
    def at_step(d: float) -> np.ndarray:
        v = list(at)
        v[j] += d
        return np.asarray(f(v), dtype=float)

    return along_branch(at_step, h)


def along_branch(at_step: Callable[[float], np.ndarray], h: float) -> np.ndarray:
    """`branch_difference` along a direction: `at_step(d)` is f moved by d along it
    (d in 0, +-h and, where the sides disagree, +-h/2)."""
    mid, hi, lo = at_step(0.0), at_step(h), at_step(-h)
    with np.errstate(invalid="ignore", over="ignore"):
        up, down = (hi - mid) / h, (mid - lo) / h
        noise = 8.0 * np.finfo(float).eps * (np.abs(mid) + np.abs(hi) + np.abs(lo)) / h
        bent = ~(np.abs(up - down) <= 1e-8 * (np.abs(up) + np.abs(down)) + noise)
        central = (hi - lo) / (2.0 * h)
        if not np.any(bent & np.isfinite(mid)):
            return np.where(np.isfinite(mid) & np.isfinite(central), central, 0.0)
        half_up, half_down = at_step(0.5 * h), at_step(-0.5 * h)
        right = (-3.0 * mid + 4.0 * half_up - hi) / h
        left = (3.0 * mid - 4.0 * half_down + lo) / h
        # (a side that is not finite -- a slot at -INF the step leaves there -- is the
        # other branch; otherwise the straighter side)
        straight_right = np.isfinite(right) & (
            ~np.isfinite(left) |
            (np.abs(half_up - 0.5 * (mid + hi)) <= np.abs(half_down - 0.5 * (mid + lo))))
        out = np.where(bent, np.where(straight_right, right, left), central)
    return np.where(np.isfinite(mid) & np.isfinite(out), out, 0.0)
