"""Where the surfaces a step crossed reach zero, at the cost of what the stepper has.

A stepper whose dense output is cheap but coarse (AUTO's odeint: a cubic through
two rows, `steppers.dense.Nodes`) first tries to make it good enough in place
(`sharpen`: a quintic through a third row); where it cannot, the crossings are
located on the coarse output, and a narrow window around the first is integrated
once more (`refine`: on AUTO, within the LSODA step the crossing is in): the
crossings of one step are solved together, the window once, and again on the
refined output.

A surface linear in the states (a gradient g) is solved on the dense output
projected on g, a function of floats with no call of the compiled surfaces; the
part of the surface that is not g.y (TIME, constants) is taken linear across the
step, and the root is checked on the surface itself, falling back to Brent's
method on it where that check fails.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from ..library.surfaces import sign
from .watch import SurfaceWatch

COARSE = 1e-7  # the first pass stops within this share of the step (before a window)
_XTOL = 4 * np.finfo(float).eps


def expected_event(recent: list[float], t: float) -> float | None:
    """How long after t (a restart) the next event may come, when the recent restarts
    keep a rhythm: events that alternate (contact, release) repeat their spacing
    every other one, so the next gap is the one two back, if that one repeated too.
    The AUTO route sizes its first chunk so (little integrated past the event)."""
    if len(recent) < 5 or recent[-1] != t:
        return None
    gap, before = recent[-2] - recent[-3], recent[-4] - recent[-5]
    return gap if abs(gap - before) <= 0.2 * gap else None


def locate_crossings(watch: SurfaceWatch, stepper, hits: list[int], m, z, ta: float,
                     tb: float, segment_start: float, ends=None
                     ) -> tuple[dict[int, float], set[int]]:
    """The root in [ta, tb] of every crossed surface in `hits` (by watched position),
    and those with nothing to bracket (they take their sign at tb). `ends`: the
    watched surfaces at ta and at tb, when the caller has them."""
    coarse = stepper.refines and not stepper.sharpen()
    interp = stepper.interpolant()
    within = _first_steps(stepper, hits, ta, tb)
    roots, departed = _roots(watch, hits, m, z, interp, ta, tb, segment_start,
                             COARSE * (tb - ta) if coarse else None, ends, within)
    if not coarse or not roots:
        return roots, departed
    # the window around the first root, and once more around where it moved to if it
    # fell outside (a first estimate on a cubic over many of LSODA's steps)
    for _ in range(2):
        first = min(roots.values())
        interp = stepper.refine(first, set(roots))
        better, _ = _roots(watch, list(roots), m, z, interp, ta, tb, segment_start, None,
                           ends, within)
        roots.update(better)
        if not better or stepper.resolved(min(roots.values()), set(roots)):
            break
    return roots, departed


def _first_steps(stepper, hits: list[int], ta: float, tb: float
                 ) -> dict[int, tuple[float, float]]:
    """Where a stepper's interval holds several of its own steps (AUTO's), the step
    each crossed surface first crosses in: a root searched over the whole interval
    may be any of an odd number of crossings (SIGN(SIN(10 t)) over a row interval of
    1: it found the third)."""
    if not stepper.refines:
        return {}
    out = {}
    for k in hits:
        step = stepper.crossing_step({k})
        if step is not None and ta <= step[0] < step[1] <= tb and step != (ta, tb):
            out[k] = step
    return out


def _roots(watch: SurfaceWatch, hits: list[int], m, z, interp, ta: float, tb: float,
           segment_start: float, xtol: float | None, ends,
           within: dict[int, tuple[float, float]] | None = None
           ) -> tuple[dict[int, float], set[int]]:
    """Each surface's root in [ta, tb]; the one in its first step there (`within`)
    where that step brackets one and the root found is past it."""
    roots: dict[int, float] = {}
    departed: set[int] = set()
    # linear surfaces first: their roots are cheap, and a nonlinear surface that
    # crosses with one of them (ABS(Y) - DH with Y - DH) is tried there first
    for k in sorted(hits, key=lambda k: watch.watched[k].gradient is None):
        tk = _linear_root(watch, k, m, z, interp, ta, tb, xtol, ends)
        if tk is None:
            tk = _shared_root(watch, k, m, z, interp, roots.values(), ta, tb)
        if tk is None:
            tk = watch.locate(k, m, z, interp, ta, tb, segment_start, xtol=xtol)
        if within and k in within and (tk is None or tk > within[k][1]):
            # (a later one of several crossings: the first is in its first step)
            first = _bracketed_root(watch, k, m, z, interp, *within[k], xtol)
            tk = first if first is not None else tk
        if tk is None:
            departed.add(k)
        else:
            roots[k] = tk
    return roots, departed


def _bracketed_root(watch: SurfaceWatch, k: int, m, z, interp, lo: float, hi: float,
                    xtol: float | None) -> float | None:
    """Surface k's root in [lo, hi] where its sign on the dense output changes across
    them (None where it does not: the step ends' states are the solver's, and the
    whole interval is searched instead)."""
    surf = watch.c.surf

    def g(t: float) -> float:
        return surf(t, interp(t).tolist(), m, z)[k]

    glo, ghi = g(lo), g(hi)
    if ghi == 0.0 and glo != 0.0:
        return hi
    if not (math.isfinite(glo) and math.isfinite(ghi)) or glo == 0.0 or \
            sign(glo) == sign(ghi):
        return None
    return brentq(g, lo, hi, xtol=xtol or _XTOL * max(abs(hi), 1e-300), rtol=_XTOL,
                  maxiter=200)


def _shared_root(watch: SurfaceWatch, k: int, m, z, interp, known, ta: float,
                 tb: float) -> float | None:
    """Surface k's root if it is at one of the roots already found: a sign change
    across a few ulps of it."""
    surf = watch.c.surf
    for t in sorted(set(known)):
        d = 64 * _XTOL * max(abs(t), 1e-300)
        lo, hi = max(ta, t - d), min(tb, t + d)
        glo = surf(lo, interp(lo).tolist(), m, z)[k]
        ghi = surf(hi, interp(hi).tolist(), m, z)[k]
        if glo == 0.0:
            return lo
        if ghi == 0.0 or (math.isfinite(glo) and math.isfinite(ghi) and
                          sign(glo) != sign(ghi)):
            return t
    return None


def _linear_root(watch: SurfaceWatch, k: int, m, z, interp, ta: float, tb: float,
                 xtol: float | None, ends) -> float | None:
    """The root of a surface linear in the states, on the projected dense output; None
    when this way does not apply (no gradient, no sign change, the check fails)."""
    g = watch.watched[k].gradient
    if g is None or not hasattr(interp, "along") or interp.t[0] != ta or interp.t[-1] != tb:
        return None
    surf = watch.c.surf
    ya, yb = interp.y[0], interp.y[-1]
    if ends is not None:
        ea, eb = ends[0][k], ends[1][k]
    else:
        ea, eb = surf(ta, ya.tolist(), m, z)[k], surf(tb, yb.tolist(), m, z)[k]
    if ea == 0.0 or eb == 0.0 or sign(ea) == sign(eb):
        return None
    # the part of the surface that is not g.y, linear across the step
    ca, cb = ea - float(g @ ya), eb - float(g @ yb)
    value = interp.along(g)
    h = tb - ta

    def e(t: float) -> float:
        return value(t) + ca + (cb - ca) * ((t - ta) / h)

    if xtol is None:
        xtol = _XTOL * max(abs(tb), 1e-300)
    root = brentq(e, ta, tb, xtol=xtol, rtol=_XTOL, maxiter=200)
    if ca != cb:  # TIME in the surface: check on the surface itself
        true = surf(root, interp(root).tolist(), m, z)[k]
        if not math.isfinite(true) or abs(true) > 1e-9 * (abs(ea) + abs(eb)):
            return None
    return root
