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
from numba import njit, types
from scipy.integrate._ivp import dop853_coefficients as _dc

from ..surfaces import DOWN, REPELS, UP, leaving
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
    STIFF_AT,
    STIFF_H_LAMBDA,
)

N_STAGES = _dc.N_STAGES
A = np.ascontiguousarray(_dc.A[:N_STAGES, :N_STAGES])
B = np.ascontiguousarray(_dc.B)
C = np.ascontiguousarray(_dc.C[:N_STAGES])
E3 = np.ascontiguousarray(_dc.E3)
E5 = np.ascontiguousarray(_dc.E5)
D = np.ascontiguousarray(_dc.D)
A_EXTRA = np.ascontiguousarray(_dc.A[N_STAGES + 1:])
C_EXTRA = np.ascontiguousarray(_dc.C[N_STAGES + 1:])
N_EXTENDED = _dc.N_STAGES_EXTENDED
POWER = _dc.INTERPOLATOR_POWER
ROWS = POWER + 4  # a step's interpolant: DOP853's terms, then both ends and their slopes

SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
EXPONENT = -1.0 / 8.0  # the error estimator's order is 7

# NaN and infinities, not exceptions, where arithmetic fails (as the model's own code)
_jit = njit(cache=True, error_model="numpy")
_leaving = _jit(leaving)  # (the run loop's own rule, compiled)

_F8, _I8 = types.float64, types.int64
_V, _M = types.float64[::1], types.float64[:, ::1]  # C-ordered vectors and matrices
# the model's functions: (t, y, m, z, p, out) -> None, the values written into out
MODEL = types.void(_F8, _V, _V, _V, _V, _V)
_FN = types.FunctionType(MODEL)
_I, _B = types.int64[::1], types.boolean[::1]


def _entry(restype, *argtypes):
    """An entry point from Python, compiled when this module is imported (from
    numba's cache after the first time), with the model's functions as pointers:
    one machine code for every model."""
    return njit(restype(*argtypes), cache=True, error_model="numpy")


STEPS_PER_CALL = 20000  # the run loop looks at its deadline and progress between calls


@_jit
def _rms(v):
    return math.sqrt(np.sum(v * v) / max(v.size, 1))


@_entry(_F8, _FN, _F8, _V, _V, _F8, _F8, _V, _V, _V, _V, _V)
def first_step(rhs, t, y, f, t_bound, max_step, rtol, atol, m, z, p):
    """SciPy's `select_initial_step` for an 8th-order pair (error order 7)."""
    n = y.size
    interval = abs(t_bound - t)
    if interval == 0.0:
        return 0.0
    scale = atol + np.abs(y) * rtol
    d0 = _rms(y / scale)
    d1 = _rms(f / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = y + h0 * f
    f1 = np.empty(n)
    rhs(t + h0, y1, m, z, p, f1)
    d2 = _rms((f1 - f) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1, interval, max_step)


@_jit
def _stages(rhs, t, y, f, h, m, z, p, K, y_new, ys):
    """One DOP853 step from (t, y) with f = rhs(t, y): K[0..12] and y_new (K[12] is
    the derivative there); returns the error norm's square terms (err5, err3)."""
    n = y.size
    K[0, :] = f
    for s in range(1, N_STAGES):
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += A[s, j] * K[j, i]
            ys[i] = y[i] + h * acc
        rhs(t + C[s] * h, ys, m, z, p, K[s])
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES):
            acc += B[j] * K[j, i]
        y_new[i] = y[i] + h * acc
    rhs(t + h, y_new, m, z, p, K[N_STAGES])


@_jit
def _error_norm(y, y_new, K, h, rtol, atol):
    n = y.size
    e5 = 0.0
    e3 = 0.0
    for i in range(n):
        scale = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol[i]
        a5 = 0.0
        a3 = 0.0
        for j in range(N_STAGES + 1):
            a5 += E5[j] * K[j, i]
            a3 += E3[j] * K[j, i]
        a5 /= scale
        a3 /= scale
        e5 += a5 * a5
        e3 += a3 * a3
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * n)


@_jit
def dense_terms(rhs, t, y, h, y_new, f_new, m, z, p, K, F, ys):
    """The step's interpolant, F[0..6] (SciPy's Dop853DenseOutput), with the three
    extra stages it needs, and its ends with their derivatives (F[7..10], for the
    cubic Hermite of `interpolate`)."""
    n = y.size
    for s in range(N_STAGES + 1, N_EXTENDED):
        a = A_EXTRA[s - N_STAGES - 1]
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += a[j] * K[j, i]
            ys[i] = y[i] + h * acc
        rhs(t + C_EXTRA[s - N_STAGES - 1] * h, ys, m, z, p, K[s])
    for i in range(n):
        F[POWER, i] = y[i]
        F[POWER + 1, i] = K[0, i]
        F[POWER + 2, i] = y_new[i]
        F[POWER + 3, i] = f_new[i]
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (f_new[i] + K[0, i])
        for r in range(POWER - 3):
            acc = 0.0
            for j in range(N_EXTENDED):
                acc += D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@_jit
def dense_at(t_old, h, y_old, F, t, out):
    """The interpolant at t (SciPy's evaluation order)."""
    x = (t - t_old) / h
    n = y_old.size
    for i in range(n):
        acc = 0.0
        for r in range(POWER - 1, -1, -1):
            acc += F[r, i]
            if (POWER - 1 - r) % 2 == 0:
                acc *= x
            else:
                acc *= 1.0 - x
        out[i] = acc + y_old[i]


@_entry(types.none, _F8, _F8, _M, types.boolean, _F8, _V)
def interpolate(t_old, h, F, cubic, t, out):
    """The step's state at t: DOP853's interpolant, or the cubic Hermite through its
    ends where that is not to be trusted -- a stability-bound step (`cubic`; see
    `steppers.ivp.ScipyStepper`) or a value that overflows inside."""
    n = out.size
    if not cubic:
        dense_at(t_old, h, F[POWER], F, t, out)
        finite = True
        for i in range(n):
            if not math.isfinite(out[i]):
                finite = False
        if finite:
            return
    s = (t - t_old) / h
    h00 = (1.0 + 2.0 * s) * (1.0 - s) ** 2
    h01 = s * s * (3.0 - 2.0 * s)
    h10 = s * (1.0 - s) ** 2
    h11 = s * s * (s - 1.0)
    for i in range(n):
        out[i] = h00 * F[POWER, i] + h01 * F[POWER + 2, i] + \
            h * (h10 * F[POWER + 1, i] + h11 * F[POWER + 3, i])


@_jit
def _stiffness(y, y_new, K, h, sc, tested, t_new):
    """Hairer's stiffness test (as `ScipyStepper._stiffness_test`): h*|lambda| from
    the last stage (c = 1) and the new point, its counts and its findings in sc
    (POSITIVE ... STIFF_H_LAMBDA, see `layout`)."""
    if sc[POSITIVE] == 0.0 and tested % 4:
        return
    n = y.size
    den = 0.0
    num = 0.0
    for i in range(n):
        acc = 0.0
        for j in range(N_STAGES - 1):
            acc += A[N_STAGES - 1, j] * K[j, i]
        d = y_new[i] - y[i] - h * acc
        den += d * d
        g = K[N_STAGES, i] - K[N_STAGES - 1, i]
        num += g * g
    if not (0.0 < den < np.inf):
        return
    sc[H_LAMBDA] = abs(h) * math.sqrt(num / den)
    if sc[H_LAMBDA] > sc[LIMIT]:
        sc[CALM] = 0.0
        sc[POSITIVE] += 1.0
        if sc[POSITIVE] == 15.0 and not sc[STIFF_AT] == sc[STIFF_AT]:
            sc[STIFF_AT] = t_new
            sc[STIFF_H_LAMBDA] = sc[H_LAMBDA]
    else:
        sc[CALM] += 1.0
        if sc[CALM] == 6.0:
            sc[POSITIVE] = 0.0


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
    n = y.size
    t, h_abs, t_bound = sc[AT], sc[STEP], sc[BOUND]
    max_step, lookahead = sc[MAX_STEP], sc[LOOKAHEAD]
    K = np.empty((N_EXTENDED, n))
    y_new = np.empty(n)
    yt = np.empty(n)
    ft = np.empty(n)
    scratch = np.empty(n)
    ys = np.empty(n)  # a stage's argument
    ne = e_a.size
    e_b = np.empty(ne)
    e0 = np.empty(ne)
    e1 = np.empty(ne)
    F = np.empty((ROWS, n))
    nm = m.size
    tks = np.full(nm, np.inf)
    m_old = np.empty(nm)
    m_new = np.empty(nm)
    at_zero = np.zeros(nm, np.bool_)
    flip = np.zeros(nm, np.bool_)
    rows = 0
    nev = 0
    nsmp = 0
    nfev = 0
    steps = 0
    ngrid = grid.size
    sampling = smp_T.size > 0
    status = BUFFER
    while True:
        if steps >= STEPS_PER_CALL or nev + nm > ev_t.size or \
                (sampling and nsmp + 2 > smp_T.size) or (rows >= out_T.size and gi < ngrid):
            status = BUFFER
            break
        # the last grid instant the rows buffer has room for (a buffer as long as the
        # rest of the run would cost in proportion to the run): a step that may go past
        # it is the next call's, with the buffer empty; only a step longer than the
        # whole buffer ends there
        last_row = gi + out_T.size - rows - 1
        row_cap = grid[last_row] if last_row < ngrid and grid[last_row] > t else np.inf
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
        rejected = False
        while True:
            if not h_abs >= min_step:  # (NaN included)
                status = SMALL
                break
            t_new = t + h_abs
            if t_new > t_bound:
                t_new = t_bound
            if t_new > row_cap:
                t_new = row_cap
            h = t_new - t
            _stages(rhs, t, y, f, h, m, z, p, K, y_new, ys)
            nfev += N_STAGES
            err = _error_norm(y, y_new, K, h, rtol, atol)
            if err < 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR, SAFETY * err ** EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                h_next = abs(h) * factor
                break
            # a NaN or an infinity in the stages (a fault) shrinks the step too
            factor = SAFETY * err ** EXPONENT if err == err and err < np.inf else MIN_FACTOR
            h_abs = abs(h) * max(MIN_FACTOR, factor)
            rejected = True
        if status == SMALL:
            break
        steps += 1
        f_new = K[N_STAGES]
        _stiffness(y, y_new, K, h, sc, sc[NSTEPS] + steps - sc[RESTARTED], t_new)
        # a stability-bound step: its rows and crossings from its ends only
        cubic = sc[POSITIVE] >= 15.0 and sc[H_LAMBDA] > sc[LIMIT]
        surf(t_new, y_new, m, z, p, e_b)
        first = -1
        simple = True
        quiet = 0
        for k in watch:
            flip[k] = False
            if _crossed(k, m[k], e_b[k], level):
                matters = 0
                if handled[k] >= QUIET:
                    matters = _silent(rhs, surf, k, t_new, y_new, m, z, p, ft, scratch, watch,
                                      level, e0, e1)
                    nfev += 3
                if matters == 1:
                    # a branch nothing uses now: followed, no restart (as the loop does)
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
        ends = t_new >= t_bound
        bad = h < sc[FLOOR]  # (the loop counts them: TIMER DELMIN, a finite-time singularity)
        for i in range(n):
            if not math.isfinite(y_new[i]):
                bad = True
        if bad:  # held as a segment's last step is, nothing located
            first = -1
            ends = True
        if first >= 0 or ends or (gi < ngrid and grid[gi] <= t_new):
            dense_terms(rhs, t, y, h, y_new, f_new, m, z, p, K, F, ys)
            nfev += 3
        t_star = t_new
        if first >= 0 and simple:
            for k in watch:
                tks[k] = np.inf
                if _crossed(k, m[k], e_b[k], level):
                    if e_a[k] == 0.0 or _crossed(k, m[k], e_a[k], level):
                        simple = False  # began on it: nothing to bracket here
                        break
                    tks[k] = _locate(surf, k, m[k], level, t, t_new, e_a[k], e_b[k], h,
                                     cubic, F, m, z, p, e0, yt)
                    t_star = min(t_star, tks[k])
        if first >= 0 and simple:
            interpolate(t, h, F, cubic, t_star, yt)
            for i in range(n):
                if not math.isfinite(yt[i]):
                    simple = False
        if first >= 0 and simple:
            # the surfaces at zero here (several cross at once at a dead zone's edge)
            # each go the way the motion takes them, in the branches decided before
            # them, as `SurfaceWatch.choose_modes`; the others must stay on their sides
            close = 8.0 * 2.220446049250313e-16 * max(abs(t_star), 1e-300)
            m_old[:] = m
            for k in watch:
                if tks[k] - t_star <= close:
                    new_mode = _direction(rhs, surf, k, m_old[k], t_star, yt, m, z, p,
                                          lookahead, ft, scratch, e0, e1)
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
        if (first >= 0 and not simple) or (ends and first < 0):
            # the run loop takes this step: its rows inside, the crossing or the
            # segment's end, by its general rules
            held_y[:] = y_new
            held_f[:] = K[N_STAGES]
            held_F[:, :] = F
            sc[CUBIC] = 1.0 if cubic else 0.0
            sc[HELD_END] = t_new
            sc[STEP] = h_next
            status = HELD
            break
        if first >= 0:
            # the rows before the crossing, in the branches before it ...
            while gi < ngrid and grid[gi] < t_star:
                out_T[rows] = grid[gi]
                interpolate(t, h, F, cubic, grid[gi], out_Y[rows])
                out_M[rows, :] = m
                rows += 1
                gi += 1
            for k in watch:
                if m_new[k] != m[k]:
                    ev_t[nev] = t_star
                    ev_k[nev] = k
                    ev_new[nev] = m_new[k]
                    ev_y[nev, :] = yt
                    ev_m[nev, :] = m
                    nev += 1
                    m[k] = m_new[k]
            # ... and the integration restarts there, in the new ones
            y[:] = yt
            h = t_star - t  # the next step tries the cut one's length, as the loop's
            t = t_star
            sc[POSITIVE] = 0.0  # the stiffness test starts again, as a new stepper's would
            sc[CALM] = 0.0
            sc[RESTARTED] = sc[NSTEPS] + steps
            rhs(t, y, m, z, p, f)
            nfev += 1
            surf(t, y, m, z, p, e_a)
            h_abs = max(h, 1e-12 * max(abs(t), 1.0))
            continue
        if quiet:
            for k in watch:
                if flip[k]:
                    m[k] = 1.0 if e_b[k] > 0.0 else (-1.0 if e_b[k] < 0.0 else 0.0)
        if sampling:
            smp_T[nsmp] = t_new
            smp_Y[nsmp, :] = y_new
            smp_M[nsmp, :] = m
            nsmp += 1
        while gi < ngrid and grid[gi] <= t_new:
            out_T[rows] = grid[gi]
            if grid[gi] == t_new:
                out_Y[rows, :] = y_new
            else:
                interpolate(t, h, F, cubic, grid[gi], out_Y[rows])
            out_M[rows, :] = m
            rows += 1
            gi += 1
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
