"""The compiled route's integration loop: Dormand-Prince 8(5,3) with its dense output,
the output rows, the switching surfaces and the crossings, compiled by numba.

The model comes in as two compiled functions of one signature (`MODEL`):
`rhs(t, y, m, z, p, out)` and `surf(t, y, m, z, p, out)` (`translate` writes them),
called through function pointers. So this loop is compiled once per machine and
kept in numba's cache, a new listing compiles only its own two functions, and a
new PARAM value (an argument, `p`) compiles nothing.

`advance` integrates from `t` towards `t_bound` with the branches `m` frozen, writing
the rows of the output instants `grid[gi:]` it passes. A crossing of a surface whose
new branch is plain (a SIGN surface of a switch, crossed transversally, the other
surfaces on their own sides afterwards) is located on the dense output by the
Illinois method, the branch changed and the integration restarted there, with no
Python between. Anything else -- a surface the loop must decide (a FINISH, a level,
one the motion slides on or grazes), the segment's last step -- is handed back as a
held step [t, tb] with its dense output, for the run loop's general rules
(`run.loop.Integrator`), exactly as a Python stepper's step would be.

SciPy's DOP853 (`scipy.integrate._ivp.rk`) is the reference for every formula:
the same coefficients, error norm, step-size control and initial step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.extending import register_jitable

from ..library.surfaces import DOWN, REPELS, UP, leaving, slides
from .dop853 import (  # noqa: F401 - first_step, MODEL: the entry points callers take
    _B,
    _F8,
    _FN,
    _I,
    _I8,
    _M,
    _V,
    MODEL,
    N_EXTENDED,
    N_STAGES,
    ROWS,
    _entry,
    _jit,
    _part,
    _stiffness,
    dense_terms,
    first_step,
    interpolate,
    step,
)
from .layout import (
    AT,
    BOUND,
    BUFFER,
    CALM,
    CUBIC,
    FLOOR,
    H_LAMBDA,
    HELD,
    HELD_END,
    LIMIT,
    LOOKAHEAD,
    MAX_STEP,
    NFEV,
    NSTEPS,
    PLAIN,
    POSITIVE,
    QUIET,
    RESTARTED,
    SMALL,
    STEP,
    STEPS,
)

_leaving = _jit(leaving)  # (the run loop's own rule, compiled)
# the library's rules that the helpers compiled as written call (a level surface's
# `level_edge` asks whether its mode `slides`): numba compiles them where called
register_jitable(slides)
STEPS_PER_CALL = 20000  # the run loop looks at its deadline and progress between calls

@_jit
def _crossed(k, mode, e, level):
    if level[k] or mode > 0.0:
        return e < 0.0
    if mode < 0.0:
        return e > 0.0
    return False


@_jit
def _locate(surf, k, mode, level, ta, tb, ga, gb, h, cubic, F, m, z, p, e, yt):
    """Illinois on surface k over the dense output: the first instant past the
    crossing (to a few ulps of TIME)."""
    a, b = ta, tb
    fa, fb = ga, gb
    side = 0
    for _ in range(200):
        if b - a <= 4.0 * 2.220446049250313e-16 * max(abs(a), abs(b), 1e-300):
            break
        t = (a * fb - b * fa) / (fb - fa)
        if not (a < t < b):
            t = 0.5 * (a + b)
        interpolate(ta, h, F, cubic, t, yt)
        surf(t, yt, m, z, p, e)
        g = e[k]
        if _crossed(k, mode, g, level) or g == 0.0:
            b, fb = t, g
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = t, g
            if side == 1:
                fb *= 0.5
            side = 1
    return b


@_jit
def _side(k, e, level):
    """Where a surface's value puts it (`SurfaceWatch.side`)."""
    if level[k]:
        return 1.0 if e < 0.0 else 0.0
    return 1.0 if e > 0.0 else (-1.0 if e < 0.0 else 0.0)


@_jit
def _silent(rhs, surf, k, t, y, m, z, p, f1, f2, watch, level, e1, e2):
    """Whether surface k's branch matters here: 0 it changes the derivatives, 1 it
    changes nothing (`SurfaceWatch.silent`), 2 it changes no derivative but the side
    another watched surface is on (`SurfaceWatch.quiet` and not `silent`: the loop
    cuts the step there, with no event of its own)."""
    mk = m[k]
    m[k] = 1.0
    rhs(t, y, m, z, p, f1)
    found = 1
    for value in (-1.0, 0.0):
        m[k] = value
        rhs(t, y, m, z, p, f2)
        for i in range(y.size):
            if f1[i] != f2[i]:
                found = 0
    if found == 1:
        m[k] = 1.0
        surf(t, y, m, z, p, e1)
        m[k] = -1.0
        surf(t, y, m, z, p, e2)
        for j in watch:
            if j != k and _side(j, e1[j], level) != _side(j, e2[j], level):
                found = 2
    m[k] = mk
    return found


@_jit
def _direction(rhs, surf, k, old, t, y, m, z, p, lookahead, f, yt, e0, e1):
    """Which side of surface k the motion goes to from (t, y) on it (as
    `SurfaceWatch.direction`): +1, -1, or 0 when the run loop must decide (sliding,
    grazing, rates that vanish)."""
    mk = m[k]
    rates = np.empty(2)
    for side in range(2):
        m[k] = 1.0 if side == 0 else -1.0
        rhs(t, y, m, z, p, f)
        surf(t, y, m, z, p, e0)
        for i in range(y.size):
            yt[i] = y[i] + lookahead * f[i]
        surf(t + lookahead, yt, m, z, p, e1)
        rates[side] = (e1[k] - e0[k]) / lookahead
    m[k] = mk
    way = _leaving(rates[0], rates[1], False)
    if way == REPELS:
        return -old
    if way == UP or way == DOWN:
        return way
    return 0.0


@_part
def _finite(v):
    for i in range(v.size):
        if not math.isfinite(v[i]):
            return False
    return True


@_part
def _hold(y_new, f_new, F, held_y, held_f, held_F, sc, cubic, t_new, h_next):
    """Hand the step to the run loop: its end, derivative, interpolant and length."""
    held_y[:] = y_new
    held_f[:] = f_new
    held_F[:, :] = F
    sc[CUBIC] = 1.0 if cubic else 0.0
    sc[HELD_END] = t_new
    sc[STEP] = h_next


@_part
def _room(grid, gi, rows, rows_size, t):
    """The last grid instant the rows buffer has room for (a buffer as long as the
    rest of the run would cost in proportion to the run): a step that may go past
    it is the next call's, with the buffer empty; only a step longer than the whole
    buffer ends there."""
    last_row = gi + rows_size - rows - 1
    return grid[last_row] if last_row < grid.size and grid[last_row] > t else np.inf


@_part
def _watch(rhs, surf, t_new, y_new, m, z, p, e_a, e_b, watch, handled, level, flip, ft,
           scratch, e0, e1):
    """The surfaces at a step's end (into e_b): (the last one crossed or departed
    that the kernel must act on, -1 if none; whether each such can be switched here,
    `simple`; how many crossed with a branch nothing uses, marked in `flip`, to be
    followed without a restart; evaluations)."""
    surf(t_new, y_new, m, z, p, e_b)
    first = -1
    simple = True
    quiet = 0
    nfev = 0
    for k in watch:
        flip[k] = False
        if _crossed(k, m[k], e_b[k], level):
            matters = 0
            if handled[k] >= QUIET:
                matters = _silent(rhs, surf, k, t_new, y_new, m, z, p, ft, scratch, watch,
                                  level, e0, e1)
                nfev += 3
            if matters == 1:
                flip[k] = True
                quiet += 1
                continue
            if handled[k] != PLAIN or matters == 2:
                simple = False
            first = k
        elif m[k] == 0.0 and not level[k] and abs(e_b[k]) > 1e-12 * (1.0 + abs(e_a[k])) \
                and e_b[k] != 0.0:
            simple = False  # departed from a surface it sat on
            first = k
    return first, simple, quiet, nfev


@_part
def _locate_all(surf, t, t_new, h, cubic, F, m, z, p, e_a, e_b, watch, level, tks, e0, yt):
    """Where in (t, t_new] each crossed surface crosses (tks; inf for the others):
    (the first instant, whether every one could be bracketed)."""
    t_star = t_new
    for k in watch:
        tks[k] = np.inf
        if _crossed(k, m[k], e_b[k], level):
            if e_a[k] == 0.0 or _crossed(k, m[k], e_a[k], level):
                return t_star, False  # began on it: nothing to bracket here
            tks[k] = _locate(surf, k, m[k], level, t, t_new, e_a[k], e_b[k], h, cubic, F,
                             m, z, p, e0, yt)
            t_star = min(t_star, tks[k])
    return t_star, True


@_part
def _switch(rhs, surf, t_star, yt, m, z, p, lookahead, watch, level, tks, m_old, m_new,
            at_zero, ft, scratch, e0, e1):
    """The branches after the crossings at t_star, into m_new (m as it was): the
    surfaces at zero there (several cross at once at a dead zone's edge) each go the
    way the motion takes them, in the branches decided before them, as
    `SurfaceWatch.choose_modes`; the others must stay on their sides. Returns
    (whether the kernel can switch them itself, evaluations)."""
    close = 8.0 * 2.220446049250313e-16 * max(abs(t_star), 1e-300)
    m_old[:] = m
    simple = True
    nfev = 0
    for k in watch:
        if tks[k] - t_star <= close:
            new_mode = _direction(rhs, surf, k, m_old[k], t_star, yt, m, z, p, lookahead,
                                  ft, scratch, e0, e1)
            nfev += 2
            if new_mode == 0.0 or new_mode == m_old[k]:
                simple = False
                break
            m[k] = new_mode
    if simple:
        for k in watch:
            at_zero[k] = tks[k] - t_star <= close
        surf(t_star, yt, m, z, p, e0)
        for k in watch:
            if not at_zero[k] and (m[k] == 0.0 or e0[k] == 0.0 or
                                   _crossed(k, m[k], e0[k], level)):
                simple = False
    m_new[:] = m
    m[:] = m_old
    return simple, nfev


@_part
def _rows(t, h, F, cubic, grid, gi, t_end, closed, y_end, m, out_T, out_Y, out_M, rows):
    """The rows at the grid instants before t_end (`closed`: up to it, the one at
    t_end taking y_end exactly), each in the branches m: (rows, gi)."""
    while gi < grid.size and (grid[gi] < t_end or (closed and grid[gi] == t_end)):
        out_T[rows] = grid[gi]
        if grid[gi] == t_end:
            out_Y[rows, :] = y_end
        else:
            interpolate(t, h, F, cubic, grid[gi], out_Y[rows])
        out_M[rows, :] = m
        rows += 1
        gi += 1
    return rows, gi


@_part
def _events(t_star, yt, m, m_new, watch, ev_t, ev_k, ev_new, ev_y, ev_m, nev):
    """Log each branch that changes at t_star (with the branches before it) and
    change it: the new count."""
    for k in watch:
        if m_new[k] != m[k]:
            ev_t[nev] = t_star
            ev_k[nev] = k
            ev_new[nev] = m_new[k]
            ev_y[nev, :] = yt
            ev_m[nev, :] = m
            nev += 1
            m[k] = m_new[k]
    return nev


@_part
def _restart(rhs, surf, t, t_star, yt, y, f, e_a, m, z, p, sc, steps):
    """The integration restarts at t_star, in the new branches: the next step tries
    the cut one's length, as the loop's; the stiffness test starts again, as a new
    stepper's would. Returns (t, the step to try)."""
    y[:] = yt
    h = t_star - t
    sc[POSITIVE] = 0.0
    sc[CALM] = 0.0
    sc[RESTARTED] = sc[NSTEPS] + steps
    rhs(t_star, y, m, z, p, f)
    surf(t_star, y, m, z, p, e_a)
    return t_star, max(h, 1e-12 * max(abs(t_star), 1.0))


@_entry(types.UniTuple(_I8, 5), _FN, _FN, _V, _V, _V, _V, _V, _V, _V, _V, _V, _I, _I, _B,
        _V, _I8, _V, _M, _M, _V, _I, _V, _M, _M, _V, _V, _M, _I8, _V, _M, _M)
def advance(rhs, surf, y, f, e_a, m, z, p, sc, rtol, atol, watch, handled, level, grid, gi,
            out_T, out_Y, out_M, ev_t, ev_k, ev_new, ev_y, ev_m, held_y, held_f,
            held_F, max_steps, smp_T, smp_Y, smp_M):
    """Integrate from (sc[AT], y) with step sc[STEP] towards sc[BOUND] (see the module's
    docstring). Returns (status, rows, events, gi, samples). In place: y, f and e_a (the
    state, its derivative and the surfaces where the integration stands), m (the
    branches, changed at located crossings) and sc (the slots of `layout`). A step
    shorter than sc[FLOOR], or one whose state is not finite, is held for the loop,
    which counts and reports those. Every row has its branches (out_M), every located
    crossing those before it (ev_m): a crossing followed without a restart (a branch
    nothing uses) is not logged. Unless smp_T is empty, every step's end that is not a
    crossing is a sample (smp_T, smp_Y, smp_M): the points RANGE reads between the rows
    (the run restarts at a crossing, which RANGE reads in its new branches)."""
    n, ne, nm = y.size, e_a.size, m.size
    t, h_abs, t_bound = sc[AT], sc[STEP], sc[BOUND]
    max_step, lookahead = sc[MAX_STEP], sc[LOOKAHEAD]
    K = np.empty((N_EXTENDED, n))
    y_new, yt, ft, scratch, ys = np.empty(n), np.empty(n), np.empty(n), np.empty(n), \
        np.empty(n)  # (ys: a stage's argument)
    e_b, e0, e1 = np.empty(ne), np.empty(ne), np.empty(ne)
    F = np.empty((ROWS, n))
    tks = np.full(nm, np.inf)
    m_old, m_new = np.empty(nm), np.empty(nm)
    at_zero, flip = np.zeros(nm, np.bool_), np.zeros(nm, np.bool_)
    rows, nev, nsmp, nfev, steps = 0, 0, 0, 0, 0
    ngrid = grid.size
    sampling = smp_T.size > 0
    status = BUFFER
    while True:
        if steps >= STEPS_PER_CALL or nev + nm > ev_t.size or \
                (sampling and nsmp + 2 > smp_T.size) or (rows >= out_T.size and gi < ngrid):
            status = BUFFER
            break
        row_cap = _room(grid, gi, rows, out_T.size, t)
        if rows > 0 and t + min(h_abs, max_step) > row_cap:
            status = BUFFER
            break
        if sc[NSTEPS] + steps >= max_steps:
            status = STEPS
            break
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = min(h_abs, max_step)
        if h_abs < min_step:
            h_abs = min_step
        if not h_abs > 0.0:
            status = SMALL  # NaN: the derivatives were not finite where it stands
            break
        ok, t_new, h, h_next, used = step(rhs, t, y, f, h_abs, min_step, min(t_bound, row_cap),
                                          m, z, p, rtol, atol, K, y_new, ys)
        nfev += used
        if not ok:
            h_abs = h_next  # (the last step tried)
            status = SMALL
            break
        steps += 1
        f_new = K[N_STAGES]
        _stiffness(y, y_new, K, h, sc, sc[NSTEPS] + steps - sc[RESTARTED], t_new)
        # a stability-bound step: its rows and crossings from its ends only
        cubic = sc[POSITIVE] >= 15.0 and sc[H_LAMBDA] > sc[LIMIT]
        first, simple, quiet, used = _watch(rhs, surf, t_new, y_new, m, z, p, e_a, e_b, watch,
                                            handled, level, flip, ft, scratch, e0, e1)
        nfev += used
        ends = t_new >= t_bound
        # a step too short (the loop counts them: TIMER DELMIN, a finite-time
        # singularity) or not finite: held as a segment's last step is, nothing located
        if h < sc[FLOOR] or not _finite(y_new):
            first = -1
            ends = True
        if first >= 0 or ends or (gi < ngrid and grid[gi] <= t_new):
            dense_terms(rhs, t, y, h, y_new, f_new, m, z, p, K, F, ys)
            nfev += 3
        t_star = t_new
        if first >= 0 and simple:
            t_star, simple = _locate_all(surf, t, t_new, h, cubic, F, m, z, p, e_a, e_b,
                                         watch, level, tks, e0, yt)
        if first >= 0 and simple:
            interpolate(t, h, F, cubic, t_star, yt)
            simple = _finite(yt)
        if first >= 0 and simple:
            simple, used = _switch(rhs, surf, t_star, yt, m, z, p, lookahead, watch, level,
                                   tks, m_old, m_new, at_zero, ft, scratch, e0, e1)
            nfev += used
        if (first >= 0 and not simple) or (ends and first < 0):
            # the run loop takes this step: its rows inside, the crossing or the
            # segment's end, by its general rules
            _hold(y_new, f_new, F, held_y, held_f, held_F, sc, cubic, t_new, h_next)
            status = HELD
            break
        if first >= 0:
            # the rows before the crossing, in the branches before it, then the
            # integration restarts there in the new ones
            rows, gi = _rows(t, h, F, cubic, grid, gi, t_star, False, yt, m, out_T, out_Y,
                             out_M, rows)
            nev = _events(t_star, yt, m, m_new, watch, ev_t, ev_k, ev_new, ev_y, ev_m, nev)
            t, h_abs = _restart(rhs, surf, t, t_star, yt, y, f, e_a, m, z, p, sc, steps)
            nfev += 1
            continue
        if quiet:  # (a branch nothing uses now: followed, no restart, as the loop does)
            for k in watch:
                if flip[k]:
                    m[k] = 1.0 if e_b[k] > 0.0 else (-1.0 if e_b[k] < 0.0 else 0.0)
        if sampling:
            smp_T[nsmp] = t_new
            smp_Y[nsmp, :] = y_new
            smp_M[nsmp, :] = m
            nsmp += 1
        rows, gi = _rows(t, h, F, cubic, grid, gi, t_new, True, y_new, m, out_T, out_Y, out_M,
                         rows)
        t = t_new
        y[:] = y_new
        f[:] = f_new
        e_a[:] = e_b
        h_abs = h_next
    sc[AT] = t
    if status != HELD:
        sc[STEP] = h_abs
    sc[NFEV] += nfev
    sc[NSTEPS] += steps
    return status, rows, nev, gi, nsmp
