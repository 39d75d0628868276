"""Sliding on one or several surfaces at once (Filippov's convex combination).

While p surfaces slide, each switch on them is in neither branch: the motion is
a combination of the 2**p corners (every sliding surface in its + or - branch),
weighted multilinearly by alpha_k, the weight of surface k's + branch:

    f(alpha) = sum over corners c of  prod_k (alpha_k if c_k = + else 1 - alpha_k) * f_c

and the weights are the ones that keep every sliding surface at zero, i.e. make
each surface's rate along f(alpha) vanish. For one surface this is Filippov's
combination, alpha = d- / (d- - d+). For several it is the bilinear (Alexander
and Seidman) choice among Filippov's convex combinations on the intersection,
which is exact whenever the model is linear in each switch's value (relays,
friction terms added to a force) and is solved here as a small linear problem
per Newton step: the rates are multilinear in alpha, and for such models one
step from alpha = 1/2 solves them.

When the weights are not unique - two switches on one surface, or surfaces whose
constraints coincide - the least-squares step takes the smallest change from
1/2, so a weight nothing constrains stays at 1/2 (its switch reads 0 between -1
and 1) and switches with alike effects share the load. A weight that would
leave [0, 1] stays at its bound, and the others carry on without it: that
surface can no longer be held, which its exit test (`SurfaceWatch.slide_exits`)
then sees.
"""

from __future__ import annotations

import itertools

import numpy as np

from .plan import SLIDE

MAX_SLIDING = 6  # 64 evaluations of the derivatives per evaluation of the field


def side_mode(mode: float, side: float, level: bool) -> float:
    """The mode of a sliding surface's branch on `side` (+1 or -1) of it: a sign
    surface's sign; a level surface's level above or below the edge it slides on
    (its mode, `plan.SLIDE`)."""
    return mode + 0.5 * side if level else side


def corner_modes(m, sliding: list[int], levels=frozenset()) -> list[list[float]]:
    """The modes of every corner, the all-plus corner first (corner c has surface
    sliding[i] in its + branch when bit i of (2**p - 1 - c) is set); `levels`: which
    surfaces are level surfaces (`side_mode`)."""
    out = []
    for signs in itertools.product((1.0, -1.0), repeat=len(sliding)):
        mc = list(m)
        for k, s in zip(sliding, reversed(signs), strict=True):
            mc[k] = side_mode(m[k], s, k in levels)
        out.append(mc)
    return out


def corner_weights(alpha: np.ndarray) -> np.ndarray:
    """The weight of every corner (order of `corner_modes`)."""
    w = np.ones(1)
    for a in alpha:
        # the new surface becomes the highest bit: + corners first
        w = np.concatenate((a * w, (1.0 - a) * w))
    return w


def combine(weights: np.ndarray, values: list[np.ndarray]) -> np.ndarray:
    """sum_c weights[c] * values[c], left to right (with one surface:
    alpha * f+ + (1 - alpha) * f-)."""
    total = weights[0] * values[0]
    for w, v in zip(weights[1:], values[1:], strict=True):
        total = total + w * v
    return total


def slide_weights(rates: np.ndarray, bounded: bool = True) -> np.ndarray:
    """The corner weights that keep the sliding surfaces at zero.

    `rates[c, j]` is surface j's rate along corner c's field (order of
    `corner_modes`). `bounded=False`: the weights not held to [0, 1] (the field's
    smooth continuation past where one reaches its bound, which the variational
    equations differentiate: `run.variational.filippov`)."""
    return corner_weights(slide_alphas(rates, bounded))


def slide_alphas(rates: np.ndarray, bounded: bool = True) -> np.ndarray:
    """The weight of each sliding surface's + branch (`slide_weights`)."""
    if rates.shape[1] == 1:
        dp, dm = float(rates[0, 0]), float(rates[1, 0])
        denom = dm - dp
        alpha = 0.5 if denom == 0 else dm / denom
        return np.array([min(1.0, max(0.0, alpha)) if bounded else alpha])
    return _solve(rates, bounded)


def _solve(rates: np.ndarray, bounded: bool = True) -> np.ndarray:
    """Projected Newton on the multilinear equations g(alpha) = 0 (see the module
    docstring), from alpha = 1/2 (projected onto [0, 1] when `bounded`)."""
    p = rates.shape[1]
    alpha = np.full(p, 0.5)
    free = np.ones(p, bool)
    scale = float(np.max(np.abs(rates))) or 1.0
    for _ in range(4 * p + 8):
        w = corner_weights(alpha)
        g = w @ rates
        if np.max(np.abs(g)) <= 1e-13 * scale or not free.any():
            break
        jac = np.empty((p, p))
        for i in range(p):
            up, down = alpha.copy(), alpha.copy()
            up[i], down[i] = 1.0, 0.0
            # multilinear: exact derivative from the two faces
            jac[:, i] = (corner_weights(up) - corner_weights(down)) @ rates
        step = np.linalg.lstsq(jac[:, free], -g, rcond=1e-10)[0]
        new = alpha.copy()
        new[free] += step
        if not bounded:
            alpha = new
            if not np.any(step):
                break
            continue
        out = (new < 0.0) | (new > 1.0)
        alpha = np.clip(new, 0.0, 1.0)
        free &= ~out
        if not np.any(step):
            break
    return alpha


__all__ = ["MAX_SLIDING", "SLIDE", "combine", "corner_modes", "corner_weights", "side_mode",
           "slide_alphas", "slide_weights"]
