"""The variational equations of the flow map, integrated along the flow: the
monodromy matrix with the saltation matrix of each located switch.

`Tangent` observes the run loop's accepted steps (each cut at the located
switches, so it lies in one branch) and carries Phi = d y(t)/d y(t0):

- across a step [ta, tb], Phi' = A(t) Phi with A the field's Jacobian
  (`jacobian.jacobian_at`: the model's own, else differences) on the step's
  dense output, by the sixth-order Magnus method on three Gauss-Legendre
  nodes (Blanes, Casas & Ros 2000): exp(Omega) Phi, exact for a branch linear
  in the states whatever the step (and an exponential, so stiff modes decay as
  they should). A step over which h |A(c3) - A(c1)| > 3e-3 is checked against
  its two halves, and halved while they disagree by more than 1e-8 (at most
  256 pieces); a step that passed makes those that vary as little trusted, one
  that failed lowers that trust;
- at a switch at t_e on surface s(t, y) = 0, from field f- to f+,
      Phi <- (I + (f+ - f-) n^T / (n . f- + ds/dt)) Phi,    n = ds/dy,
  surface after surface when several change at once (exact when they are one
  surface written twice, like the hoist's |Y| = DH and Y = DH). A switch on
  TIME alone (n = 0) has no saltation.

- while surfaces slide, A is the Jacobian of Filippov's field (the combination
  of their branches that keeps them at zero, as the run integrates it, its
  weights not held to [0, 1]: `filippov`); entering a surface is a switch whose
  f+ is that field (the saltation keeps the tangent on it: n . Phi = 0 after),
  and leaving it is none: the field is continuous there, a weight having reached
  0 or 1 (Dieci and Lopez 2011, "Sliding motion on discontinuity surfaces of high
  co-dimension"); a start on a sliding surface is an entry for the columns that
  move the start off it (`_onto_surfaces`).

`ProgramTangent` also carries the memory values z (z' = 0 between updates): at an
update z = mem(t, y, z) (a step's end, a located switch: ZHOLD holding where its
trigger crosses) the update's Jacobian applies, with y's total derivative
S + f dt/dp and the update's rate in TIME where the switch's instant moves; an
instant a slot holds (CSMP's PULSE end) jumps the tangent by (f- - f+) times that
slot's row (`_wake`). A play (HSTRSS, BCKLSH) is read on the branch the motion
takes (`leaned`: following its input where the input pushes it, else holding),
and a step in which one engages is split there (`engaged`). DELAY's store is
sampled inside the steps as the run samples it, the tangent cut at each instant;
where a free delay moves those instants (P/N apart), each sample's map applies at
its moving instant and the store is differenced along the tangent, its instants
moving with the delay (`along_clock`, `_along`).

What it does not handle it says (`Tangent.failed`), and the flow map then
takes central differences of whole flows instead: a state reset (MODINT; a
`ParameterTangent` follows one: `_reset`), a
memory value the field (or an output asked for) reads changing along the way
where the memory is not carried (the flow map's),
a crossing where the flow is tangent to the surface (n . f- ~ 0), two PULSE
trains that turn at one instant a data value moves apart in a field that is not
the sum of their effects (a product of pulses: the derivative differs from either
side). A train instant a data value moves (PULSE(TZ, P, W): first + k period)
jumps the tangent by (f- - f+) dt/dp, dt/dp from the same instant of that train in
the moved code, each train its own where several turn at once.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from ..codegen.jacobian import for_parameters
from .dense import sample, sample_step
from .jacobian import STEP, along_branch, branch_difference, jacobian_at
from .plan import slides, sliding_in
from .slide import combine, corner_weights, side_mode, slide_alphas

_C = np.array([0.5 - math.sqrt(15) / 10, 0.5, 0.5 + math.sqrt(15) / 10])
VARIATION = 3e-3  # h |A(c3) - A(c1)| above this: the step is checked against its halves
AGREE = 1e-8  # whole step and halves closer than this (relative): the halves are taken
HELD = 1e-9  # a sliding weight past [0, 1] by more: the motion is on that branch
MAX_DEPTH = 8
LEAN = 1e3 * STEP  # how far a pushed play's memory is put into its clamp (`leaned`)


def _comm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a @ b - b @ a


def exp_moving(omega: np.ndarray, n: int | None) -> np.ndarray:
    """expm(omega) for a matrix whose rows past the first n are zero (the tangent's
    values and memory do not move between instants; None: no such rows): [[e^X,
    phi1(X) B], [0, I]] with X, B its first n rows, phi1 from the 2n-square [[X, I],
    [0, 0]] -- where that is the smaller (a store of a hundred slots carried by one
    state)."""
    size = len(omega)
    if n is None or 2 * n >= size:
        return expm(omega)
    aug = np.zeros((2 * n, 2 * n))
    aug[:n, :n] = omega[:n, :n]
    aug[:n, n:] = np.eye(n)
    e = expm(aug)
    out = np.eye(size)
    out[:n, :n] = e[:n, :n]
    out[:n, n:] = e[:n, n:] @ omega[:n, n:]
    return out


def magnus6(a1: np.ndarray, a2: np.ndarray, a3: np.ndarray, h: float, n: int | None = None
            ) -> np.ndarray:
    """exp(Omega) over a step h from A at the three Gauss-Legendre nodes (A's rows past
    the first n zero: `exp_moving`)."""
    b1 = h * a2
    b2 = math.sqrt(15) * h / 3 * (a3 - a1)
    b3 = 10 * h / 3 * (a3 - 2 * a2 + a1)
    c1 = _comm(b1, b2)
    c2 = -_comm(b1, 2 * b3 + c1) / 60
    omega = b1 + b3 / 12 + _comm(-20 * b1 - b3 + c1, b2 + c2) / 240
    return exp_moving(omega, n)


class Tangent:
    """Observer of a flow: Phi = d y(t)/d y(t0)[:, columns] (see the module)."""

    fractions = np.concatenate([[0.0], _C, [1.0]])  # of each step, where it samples
    # the outputs it is read for, besides the states: positions, or "all" (the flow
    # map's: None, the states only)
    outputs: list[int] | str | None = None

    def _outputs_read(self, t: float, y: np.ndarray, m, z, z_prev) -> bool:
        """Whether one of `outputs` reads memory that changed from z_prev to z."""
        yl = y.tolist()
        now, before = self.c.out(t, yl, m, z), self.c.out(t, yl, m, z_prev)
        idx = range(len(now)) if self.outputs == "all" else self.outputs
        return any(now[i] != before[i] for i in idx)

    def __init__(self, c, watch, floor: np.ndarray, n: int, columns) -> None:
        self.c, self.watch, self.floor = c, watch, floor
        self._phi = np.eye(n)[:, list(columns)]
        # steps on one linear branch (the same Jacobian A throughout) are carried
        # as one: exp((h1 + h2 + ...) A), taken when A changes or Phi is read
        self._pending: list | None = None  # [A, the steps' total length]
        self.prev: tuple | None = None  # (tb, y(tb), modes, memory) of the last step
        self._lean: tuple | None = None  # (its memory, that memory `leaned`)
        self.failed: str | None = None
        self._shift: np.ndarray | None = None  # d t/d p of the instant being joined
        # the last instant switches turned at, and the d t/d p of those that changed
        # the field
        self._turned: tuple[float, list[np.ndarray]] = (-math.inf, [])
        # each crossing's d t/d p at the instant being joined, and whether its jump
        # changes the field (`_saltation`)
        self._turn_shifts: list[tuple[np.ndarray, bool]] = []
        # steps whose h |A(c3) - A(c1)| is at most this need no check against halves
        self._trusted = VARIATION

    @property
    def phi(self) -> np.ndarray:
        self._flush()
        return self._phi

    def _flush(self) -> None:
        if self._pending is not None:
            a, h = self._pending
            self._pending = None
            self._phi = exp_moving(h * a, self._moving) @ self._phi

    # the tangent's variables that move between instants: the first these many (None:
    # all; `ParameterTangent`: the states, its values and memory held)
    _moving: int | None = None

    def value(self, fn: str, code, t: float, y, m, z):
        """`fn` ("rhs" or "surf") of the generated functions `code` at (t, y): while a
        surface slides, "rhs" is Filippov's field of that code (`filippov`)."""
        if fn == "rhs" and sliding_in(m):
            weights, modes = filippov(self.watch, code, t, y, m, z, self.floor)
            yl = [float(v) for v in y]
            return combine(weights, [np.asarray(code.rhs(t, yl, mc, z), dtype=float)
                                     for mc in modes])
        return getattr(code, fn)(t, [float(v) for v in y], m, z)

    def jacobian(self, t: float, y: np.ndarray, m, z) -> np.ndarray:
        c, value = self.c, self.value
        return jacobian_at(c, lambda v: value("rhs", c, t, v, m, z), t, y, m, z,
                           self.floor)[0]

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if self.failed is not None:
            return
        ya = np.asarray(interp(ta), dtype=float)
        if sliding_in(m):
            m = held(self.watch, self.c, ta, ya, m, z, self.floor)
        zl = self.leaned(ta, ya, m, z)
        if self.prev is not None:
            self._join(ta, ya, m, z, zl)
            if self.failed is not None:
                return
        elif sliding_in(m):
            self._onto_surfaces(ta, ya, m, zl)
            if self.failed is not None:
                return
        pieces = []
        if tb > ta:
            # (a play that engages inside the step -- its input reaching the held value:
            # the field's Jacobian changes there, with no switch to cut the step at)
            te = self.engaged(ta, tb, interp, m, z, zl)
            if te is None:
                pieces.append((ta, tb, zl))
            else:
                after = self.leaned(te, np.asarray(interp(te), dtype=float), m, z)
                pieces += [(ta, te, zl), (te, tb, after)]
                zl = after
        for u, v, zs in pieces:
            step = self._propagate(u, v, interp, m, zs, 0)
            if step is not None:
                self._flush()
                self._phi = step @ self._phi
        self.prev = (tb, np.asarray(interp(tb), dtype=float), list(m), list(z))
        self._lean = (list(z), zl)

    def leaned(self, t: float, y: np.ndarray, m, z) -> list:
        """The memory z as the derivatives read it from (t, y) on (`ProgramTangent`:
        a play leaning on an edge of its clamp)."""
        return z

    def engaged(self, ta: float, tb: float, interp, m, z, zl) -> float | None:
        """Where in (ta, tb) a play held at ta starts to follow its input
        (`ProgramTangent`), or None."""
        return None

    def _propagate(self, ta: float, tb: float, interp, m, z, depth: int) -> np.ndarray | None:
        """exp(Omega) over [ta, tb]; None when the step is on a linear branch and
        was added to the pending one (depth 0 only)."""
        h = tb - ta
        if depth:
            t1, t2, t3 = ta + _C * h
            ys = sample(interp, (t1, t2, t3))
        else:  # (the instants the step's observers share)
            times, ys = sample_step(interp, ta, tb, self.fractions)
            (t1, t2, t3), ys = times[1:4], ys[:, 1:4]
        a1 = self.jacobian(t1, ys[:, 0], m, z)
        a3 = self.jacobian(t3, ys[:, 2], m, z)
        change = float(np.max(np.abs(a3 - a1)))
        if change <= 1e-13 * float(np.max(np.abs(a1))):
            # the same Jacobian along the step: a linear branch
            if depth:
                return exp_moving(h * a1, self._moving)
            if self._pending is not None and np.array_equal(self._pending[0], a1):
                self._pending[1] += h
            else:
                self._flush()
                self._pending = [a1, h]
            return None
        a2 = self.jacobian(t2, ys[:, 1], m, z)
        whole = magnus6(a1, a2, a3, h, self._moving)
        if h * change <= self._trusted or depth >= MAX_DEPTH:
            return whole
        # the step against its two halves (Richardson): where they agree, the halves
        # are taken, and steps that vary as little are trusted from then on; else each
        # half is refined in turn, and the trust lowered (DOP853's long steps on a Hopf
        # cycle left the monodromy 2e-5 off with a fixed bound on the variation)
        mid = 0.5 * (ta + tb)
        halves = [self._magnus_on(u, v, interp, m, z) for u, v in ((ta, mid), (mid, tb))]
        if np.max(np.abs(halves[1] @ halves[0] - whole)) <= \
                AGREE * max(1.0, float(np.max(np.abs(whole)))):
            self._trusted = max(self._trusted, 0.25 * h * change)
            return halves[1] @ halves[0]
        self._trusted = max(VARIATION, min(self._trusted, 0.5 * h * change))
        return self._propagate(mid, tb, interp, m, z, depth + 1) @ \
            self._propagate(ta, mid, interp, m, z, depth + 1)

    def _magnus_on(self, ta: float, tb: float, interp, m, z) -> np.ndarray:
        """exp(Omega) over [ta, tb] at its own three Gauss-Legendre nodes."""
        times = ta + _C * (tb - ta)
        ys = sample(interp, times)
        return magnus6(*(self.jacobian(t, ys[:, i], m, z) for i, t in enumerate(times)),
                       tb - ta, self._moving)

    def _join(self, t: float, y: np.ndarray, m, z, zl=None) -> None:
        """What happened between the last step and this one: switches (saltation),
        or something the variational equations do not follow. `zl`: z `leaned`, as
        the derivatives read it (the last step's memory likewise)."""
        if zl is None:
            zl = self.leaned(t, y, m, z)
        t_prev, y_prev, m_prev, z_prev = self.prev
        self._shift, self._turn_shifts = None, []
        # (a reset whose switch turns straight back -- MODINT's sawtooth, reset to its
        # IC and integrating again at one instant -- leaves the modes as they were)
        if self.watch.resets and np.any(np.abs(y - y_prev) > 1e-6 * scale_of(y, self.floor)):
            self._reset(t, y_prev, y, m_prev, m, z_prev, z)
            return
        moved = z != z_prev and self._memory_moved(t, y, m_prev, m, z_prev, z)
        if self.failed is not None:
            return
        if self._lean is not None and self._lean[0] == list(z_prev):
            z_prev = self._lean[1]
        # leaving a sliding surface is no jump where the field is continuous there (a
        # weight having reached 0 or 1); where another switch at the instant ends the
        # slide (a push on TIME), that switch's jump is to the branch left on
        exits = [k for k in range(len(m)) if slides(m_prev[k]) and not slides(m[k])]
        if not self._trains_apart(t, y, m_prev, m, z_prev):
            return
        changed = [k for k in range(len(m)) if m[k] != m_prev[k] and k not in exits]
        # (a switch whose surface is flat in the states and TIME here -- it reads a level
        # function's level, AINT(QNTZR(0.5, X)) -- jumps with the one that crosses: its
        # change is that crossing's, at that crossing's instant; or with a slide's exit,
        # a relay reading the level the motion leaves the edge to)
        carried = [k for k in changed if self._flat(k, t, y, m_prev, z_prev)] \
            if len(changed) > 1 or exits else []
        crossing = [k for k in changed if k not in carried]
        ordered = self._in_any_order(t, y, crossing, carried, exits, m_prev, m, z_prev, zl) \
            if len(crossing) > 1 else {}
        if ordered is None:
            return
        jump = self._through(crossing, t, y, carried, exits, m_prev, m, z_prev, zl)
        if jump is None:
            return
        phi = self.phi
        self._phi = jump @ phi  # (the steps before the switches first)
        for j, moved_apart in ordered.items():  # (each column in the order it turns in)
            self._phi[:, j] = moved_apart @ phi[:, j]
        if changed:
            # (each crossing's d t/d p: a switch on TIME alone that no value moves has
            # none)
            self._turned = (t, [shift for shift, bends in self._turn_shifts if bends])
            if not self._turn_apart():
                return
        if moved:
            self._update_memory(t, y, m_prev, m, z_prev, z)
        self._wake(t, y, m, zl)

    def _trains_apart(self, t: float, y: np.ndarray, m_prev, m, z) -> bool:
        """Whether the PULSE trains that turn at t can be followed one by one
        (`ParameterTangent`: their instants do not move here)."""
        return True

    def _through(self, order: list[int], t: float, y: np.ndarray, carried, exits, m_prev,
                 m, z_prev, zl) -> np.ndarray | None:
        """The jump of the switches `order` crossing at t one after another: their
        saltations' product (None, `failed` said, where one has none)."""
        current, mem, total = list(m_prev), z_prev, np.eye(len(self._phi))
        for i, k in enumerate(order):
            after = list(current)
            after[k] = m[k]
            for e in exits:
                after[e] = m[e]
            if i == len(order) - 1:
                for j in carried:
                    after[j] = m[j]
            s = self._saltation(k, t, y, current, after, mem, zl)
            if s is None:
                return None
            total, current, mem = s @ total, after, zl
        return total

    def _in_any_order(self, t: float, y: np.ndarray, crossing: list[int], carried, exits,
                      m_prev, m, z_prev, zl) -> dict[int, np.ndarray] | None:
        """Switches that cross at t together, where a value moves their instants
        apart: its side decides which turns first, and the jumps taken in the two
        orders must agree (separate effects, STEP(T1) + STEP(T2)); where they do not
        (STEP(T1)*STEP(T2) at T1 = T2, T1 free: the forcing starts at T1 on one side,
        at T2 on the other) the derivative differs from either side: None, `failed`
        said. Else each such column's jump, in the order the switches turn in (those
        moved together kept together: T1 and T3 of STEP(T1) STEP(T2) (1 - STEP(T3)),
        T2 free, never have T2 between them)."""
        saved = (self._shift, self._turn_shifts)
        ordered: dict[int, np.ndarray] = {}
        try:
            shifts = []
            for k in crossing:  # (each one's first-order shift, from before the instant)
                self._turn_shifts = []
                after = list(m_prev)
                after[k] = m[k]
                if self._saltation(k, t, y, m_prev, after, z_prev, zl) is None:
                    return None
                shifts.append(self._turn_shifts[-1][0] if self._turn_shifts else None)
            phi = self.phi
            products: dict[tuple, np.ndarray | None] = {}  # (an order's, built once)

            def through(order: tuple) -> np.ndarray | None:
                if order not in products:
                    products[order] = self._through(list(order), t, y, carried, exits,
                                                    m_prev, m, z_prev, zl)
                return products[order]

            for j in range(phi.shape[1]):
                key = [0.0 if s is None else float(s[j]) for s in shifts]
                rank = _ranks(key)
                if len(set(rank)) < 2:
                    continue
                up, down = (tuple(crossing[i] for i in sorted(
                    range(len(crossing)), key=lambda i: (sign * rank[i], i)))
                    for sign in (1, -1))
                a, b = through(up), through(down)
                if a is None or b is None:
                    return None
                ua, ub = a @ phi[:, j], b @ phi[:, j]
                if not np.allclose(ua, ub, rtol=1e-9,
                                   atol=1e-12 * max(1.0, float(np.abs(ua).max()))):
                    self.failed = ("two switches turn at one instant that a data value "
                                   "moves apart, and the order they turn in changes the "
                                   "jump: its derivative differs from either side")
                    return None
                ordered[j] = a
            return ordered
        finally:
            self._shift, self._turn_shifts = saved

    def _turn_apart(self) -> bool:
        """Whether the switch that turned last (`_turned`) can be followed
        (`ProgramTangent`: not where a store samples at its instant, the two moved
        apart by a value)."""
        return True

    def _flat(self, k: int, t: float, y: np.ndarray, m, z) -> bool:
        """Whether surface k neither moves with the states nor with TIME at (t, y) in
        the branches m (it reads only levels or memory), and is no PULSE train's."""
        if self.watch.watched[k].surface in self.c.train_surfaces:
            return False
        try:
            return not np.any(self._gradient(k, t, y, m, z)) and \
                surface_time_rate(self.c, k, t, y, m, z) == 0.0
        except (ArithmeticError, ValueError):
            return False

    def _wake(self, t: float, y: np.ndarray, m, z) -> None:
        """An instant a memory slot holds, reached at t (`ProgramTangent`)."""

    def _reset(self, t: float, y_prev: np.ndarray, y: np.ndarray, m_prev, m, z_prev, z
               ) -> None:
        """A state reset at t (MODINT) as the modes went from m_prev to m: the flow
        map's tangent does not follow it (`ParameterTangent` does)."""
        self.failed = "a state is reset"

    def _memory_moved(self, t: float, y: np.ndarray, m_prev, m, z_prev, z) -> bool:
        """Whether the memory's change from z_prev to z is the tangent's to follow
        (`ProgramTangent` carries the memory); here it is not: one the derivatives or
        an output asked for read says so (`failed`), as d/dp = 0 would be read there."""
        if self.c.rhs(t, y.tolist(), m, z) != self.c.rhs(t, y.tolist(), m, z_prev):
            self.failed = "a memory value the derivatives read changes"
        elif self.outputs is not None and self._outputs_read(t, y, m, z, z_prev):
            self.failed = "a memory value an output reads changes (ZHOLD's held value)"
        return False

    def _update_memory(self, t: float, y: np.ndarray, m_prev, m, z_prev, z) -> None:
        """The memory updated at t (`ProgramTangent`)."""

    def _saltation(self, k: int, t: float, y: np.ndarray, before, after, z_before, z_after
                   ) -> np.ndarray | None:
        jump = self._jump(k, t, y, before, after, z_before, z_after)
        if jump is None:
            return None
        g, diff, rate = jump
        if rate is None:
            return np.eye(len(y))  # a switch on TIME alone: the instant does not move
        return np.eye(len(y)) + np.outer(diff, g) / rate

    def _onto_surfaces(self, t: float, y: np.ndarray, m, z) -> None:
        """The flow starts on surfaces that slide: a column of the tangent that moves
        the start off one (n . Phi + ds/dp != 0, the belt's speed VB of a block
        stuck on it) comes back to it as the flow would, on the branch it is then
        on (+ where the move is to s > 0), and takes that entry's jump."""
        n = len(y)
        for k in [k for k, v in enumerate(m) if slides(v)]:
            normal = self._normal(k, t, y, m, z)
            moves = normal @ self.phi
            if not np.any(moves):
                continue
            field = np.asarray(self.value("rhs", self.c, t, y, m, z), dtype=float)
            for sign in (1.0, -1.0):
                cols = np.flatnonzero(moves * sign > 0)
                if not len(cols):
                    continue
                side = list(m)
                side[k] = sign
                f = np.asarray(self.value("rhs", self.c, t, y, side, z), dtype=float)
                rate = float(normal[:n] @ f) + surface_time_rate(self.c, k, t, y, side, z)
                if rate * sign >= 0:  # (that branch does not lead back to the surface)
                    self.failed = "a sliding start that a data value moves off its surface"
                    return
                self._flush()
                self._phi[:n, cols] += np.outer(field - f, moves[cols]) / rate

    def _normal(self, k: int, t: float, y: np.ndarray, m, z) -> np.ndarray:
        """d s_k / d (the tangent's variables): the states' gradient (`_gradient`)."""
        return self._gradient(k, t, y, m, z)

    def _gradient(self, k: int, t: float, y: np.ndarray, m, z) -> np.ndarray:
        return surface_gradient(self.watch, self.c, k, t, y, m, z, self.floor)

    def _jump(self, k: int, t: float, y: np.ndarray, before, after, z_before, z_after):
        """(n = ds/dy, f+ - f-, n . f- + ds/dt) of switch k at (t, y); rate None for a
        switch on TIME alone that has no rate (a PULSE train's); None (and `failed`
        said) where the flow is tangent."""
        c = self.c
        g = self._gradient(k, t, y, before, z_before)
        yl = y.tolist()
        f_minus = np.asarray(self.value("rhs", c, t, yl, before, z_before), dtype=float)
        f_plus = np.asarray(self.value("rhs", c, t, yl, after, z_after), dtype=float)
        if not np.any(g) and self.watch.watched[k].surface in c.train_surfaces:
            # (PULSE's train: its surface jumps where it turns, no rate to be had there)
            return g, f_plus - f_minus, None
        st = surface_time_rate(c, k, t, y, before, z_before)
        if not np.any(g):
            # a switch on TIME alone (STEP(T1), FSW(TIME - T1, ...)): its instant moves
            # by -(ds/dp)/(ds/dt) with a data value, the states not at all
            return g, f_plus - f_minus, (st if st != 0 else None)
        rate = float(g @ f_minus) + st
        if abs(rate) <= 1e-9 * (float(np.abs(g) @ np.abs(f_minus)) + abs(st)) or rate == 0:
            self.failed = "the flow is tangent to a switching surface"
            return None
        return g, f_plus - f_minus, rate


def _ranks(keys: list[float]) -> list[int]:
    """Each key's rank among the distinct ones, keys within 1e-9 of each other one."""
    order = sorted(range(len(keys)), key=lambda i: keys[i])
    rank, out, last = -1, [0] * len(keys), None
    for i in order:
        if last is None or keys[i] - last > 1e-9 * max(abs(last), 1.0) + 1e-12:
            rank += 1
            last = keys[i]
        out[i] = rank
    return out


def central_difference(f, at: list[float], j: int, h: float) -> np.ndarray:
    """d f / d at[j] by a central difference (`branch_difference`'s, where f is
    smooth)."""
    hi, lo = list(at), list(at)
    hi[j] += h
    lo[j] -= h
    return (np.asarray(f(hi), dtype=float) - np.asarray(f(lo), dtype=float)) / (hi[j] - lo[j])


def one_sided(up: np.ndarray, down: np.ndarray) -> np.ndarray:
    """A derivative from the one-sided differences `up` and `down` of a value moved
    by a data value: their mean where they agree; where they do not (a sign the value
    moves across, a clamp's kink within the step), the smaller: the side that neither
    jumps nor bends (a clamp's held side is flat). No half steps of the value are to
    be had for `branch_difference`'s straighter side."""
    # (a kink or a jump within the step leaves one side flat or the two far apart;
    # curvature alone parts them by about STEP of their size)
    apart = np.abs(up - down) > 1e-2 * (np.abs(up) + np.abs(down)) + 1e-12
    return np.where(apart, np.where(np.abs(up) <= np.abs(down), up, down), 0.5 * (up + down))


def scale_of(y: np.ndarray, floor: np.ndarray) -> np.ndarray:
    return np.maximum(np.abs(y), floor)


def filippov(watch, code, t: float, y, m, z, floor) -> tuple[np.ndarray, list[list[float]]]:
    """The weights of the corners of the surfaces sliding in m (every one in its +
    or - branch: `slide.corner_modes`) and the corners' modes, under the generated
    functions `code`: the weights that keep the sliding surfaces at zero, from their
    rates along each corner; with one surface, alpha = d- / (d- - d+) for the +
    branch. Not held to [0, 1] as the run holds them: the tangent differentiates
    the field, and a difference that steps past where a weight reaches its bound
    (the surface's exit, which a moved data value moves) would put a kink in it.
    A rate is the surface's gradient (its own when it is linear in the states, as
    the run's) times the field, plus its rate in TIME, by central differences
    otherwise (steps STEP max(|y|, floor)): the run's one-sided look-ahead has a
    rounding noise of about 1e-8, which the tangent's own differences would make
    1e-3 of the weight's."""
    alphas, modes = _alphas(watch, code, t, y, m, z, floor)
    return corner_weights(alphas), modes


def _alphas(watch, code, t: float, y, m, z, floor) -> tuple[np.ndarray, list[list[float]]]:
    """`filippov`'s weight of each sliding surface's + branch, and the corners."""
    ks = watch.sliding(m)
    yv = np.asarray(y, dtype=float)
    modes = watch.corners(t, yv, m, z, ks)
    yl = yv.tolist()
    # (a level surface's slope read on its edge, as the run's rates: `_rated`)
    slopes = [_surface_slope(watch, code, k, t, yv, m, z, floor) for k in ks]
    rates = np.array([[float(g @ f) + st for g, st in slopes]
                      for f in (np.asarray(code.rhs(t, yl, mc, z), dtype=float)
                                for mc in modes)])
    return slide_alphas(rates, bounded=False), modes


def held(watch, code, t: float, y, m, z, floor) -> list[float]:
    """The branches the run's field is in at (t, y): m, except that a surface still
    marked sliding whose weight is past its bound (a push on TIME at a breakpoint
    ends the slide at once; the run, holding the weight there, moves on the branch
    before it marks the exit a step later) is on that branch."""
    if not sliding_in(m):
        return list(m)
    alphas, _ = _alphas(watch, code, t, y, m, z, floor)
    out = list(m)
    for k, a in zip(watch.sliding(m), alphas, strict=True):
        if a > 1.0 + HELD:
            out[k] = side_mode(m[k], 1.0, k in watch.levels)
        elif a < -HELD:
            out[k] = side_mode(m[k], -1.0, k in watch.levels)
    return out


def _surface_slope(watch, code, k: int, t: float, y: np.ndarray, m, z, floor
                   ) -> tuple[np.ndarray, float]:
    """(d s_k/d y, d s_k/d TIME) at (t, y) under `code` (see `filippov`); a surface
    linear in the states has no rate in TIME here, as in the run's own rates."""
    if watch.watched[k].gradient is not None:
        return np.asarray(watch.watched[k].gradient, dtype=float), 0.0
    return surface_gradient(watch, code, k, t, y, m, z, floor), \
        surface_time_rate(code, k, t, y, m, z)


def surface_gradient(watch, code, k: int, t: float, y: np.ndarray, m, z, floor
                     ) -> np.ndarray:
    """d s_k / d y at (t, y) under `code`: the surface's own when it is linear in the
    states, else central differences (steps STEP max(|y|, floor))."""
    g = watch.watched[k].gradient
    if g is not None:
        return np.asarray(g, dtype=float)
    y = np.asarray(y, dtype=float)
    h = STEP * scale_of(y, floor)
    grad = np.empty(len(y))
    for j in range(len(y)):
        up, down = y.copy(), y.copy()
        up[j] += h[j]
        down[j] -= h[j]
        grad[j] = (code.surf(t, up.tolist(), m, z)[k] -
                   code.surf(t, down.tolist(), m, z)[k]) / (up[j] - down[j])
    return grad


def surface_time_rate(code, k: int, t: float, y, m, z) -> float:
    """d s_k / d TIME at (t, y) under `code`, by a central difference."""
    ht = STEP * max(abs(t), 1.0)
    yl = [float(v) for v in y]
    return (code.surf(t + ht, yl, m, z)[k] - code.surf(t - ht, yl, m, z)[k]) / (2.0 * ht)


def watch_of(watch, code):
    """The run's surface watch over other generated functions of the same model (a
    data value moved: `ParameterTangent`'s variants), for their sliding field."""
    if watch.c is code:
        return watch
    other = copy.copy(watch)
    other.c, other.y0 = code, code.y0
    return other


class ParameterTangent(Tangent):
    """Tangent of the flow with respect to data values: d y(t)/d p for the q values
    p, carried as the flow's tangent on the states augmented by p (p' = 0), whose
    matrix is [[A, F_p], [0, 0]] with F_p = d f/d p, and whose jump at a switch takes
    the surface's own dependence on p in (n = [ds/dy, ds/dp]). `variants[j]` are the
    run's generated functions with p_j moved by +h_j and -h_j (`ModelCode`, bound to
    other constants: no compilation), for F_p and ds/dp by central differences at
    the same TIME, states, branches and memory; `start` = d y(t0)/d p.

    `exact`, when given, is d P/d p for the constants P the generated functions read
    by name (a row each, in the order of `codegen.jacobian.ParameterJacobian.names`):
    F_p and ds/dp are then those functions' derivatives in P, from their equations
    (`for_parameters`), times it -- exact to rounding -- except in a slide, whose
    weights the values move too, and a PULSE train's surfaces (there, and for a
    function the differentiation does not take, the variants' differences)."""

    def __init__(self, c, watch, floor: np.ndarray, start: np.ndarray,
                 variants: list[tuple[object, object, float]],
                 outputs: list[int] | None = None, exact: np.ndarray | None = None) -> None:
        n, q = start.shape
        super().__init__(c, watch, floor, n + q, range(n, n + q))
        self._phi = np.vstack([start, np.eye(q)])
        self.n, self.variants, self.exact = n, variants, exact
        self._moving = n
        self.outputs = "all" if outputs is None else outputs  # (observed: their memory too)

    def _by_p(self, fn: str, t: float, yl: list, m, z) -> np.ndarray:
        """d fn(t, y, m, z) / d p, a column per value (fn: "rhs" or "surf"). The field's
        where the one-sided differences disagree (a play's clamp that a value moves,
        within h of its kink) is the side that does not bend (`one_sided`); a
        surface's is central (a train's, which jumps where the value moves its
        instant, says so by its size: `_saltation`)."""
        # (a train's surface jumps where a value moves its instant: only whether it
        # moves counts, `_train_shift` says by how much, from the variants' trains)
        if self.exact is not None and not (sliding_in(m) if fn == "rhs" else
                                           self.c.train_surfaces):
            out = None
            try:
                out = for_parameters(self.c, fn).dense(t, yl, m, z) @ self.exact
            except NotImplementedError:  # (statements it does not follow: never)
                self.exact = None
            except (ArithmeticError, ValueError):  # (a rule with no value here: SQRT at 0)
                out = None
            if out is not None and np.all(np.isfinite(out)):
                return out
        cols = []
        # (a play's clamp is the only kink the field has in p between instants, its
        # branches frozen: without one, the central difference)
        centre = np.asarray(self.value(fn, self.c, t, yl, m, z), dtype=float) \
            if fn == "rhs" and self.variants and self.c.play_slots else None
        for plus, minus, h in self.variants:
            hi = np.asarray(self.value(fn, plus, t, yl, m, z), dtype=float)
            lo = np.asarray(self.value(fn, minus, t, yl, m, z), dtype=float)
            cols.append((hi - lo) / (2.0 * h) if centre is None else
                        one_sided((hi - centre) / h, (centre - lo) / h))
        return np.array(cols).T

    def _by_data(self, fn: str, t: float, y: np.ndarray, m, z) -> np.ndarray:
        """d fn / d (the tangent's variables past the states): the data values'."""
        return self._by_p(fn, t, np.asarray(y, dtype=float).tolist(), m, z)

    def jacobian(self, t: float, y: np.ndarray, m, z) -> np.ndarray:
        n, size = self.n, len(self._phi)
        out = np.zeros((size, size))
        out[:n, :n] = Tangent.jacobian(self, t, y, m, z)
        out[:n, n:] = self._by_data("rhs", t, y, m, z)
        return out

    def _normal(self, k: int, t: float, y: np.ndarray, m, z) -> np.ndarray:
        return np.concatenate([self._gradient(k, t, y, m, z),
                               self._by_data("surf", t, y, m, z)[k]])

    def shift_of(self, g: np.ndarray, rest: np.ndarray, rate: float) -> np.ndarray:
        """d t/d p of a crossing at rate `rate` of a surface whose gradient is `g` in
        the states and `rest` past them: -(n . Phi)/rate."""
        phi, n = self.phi, self.n
        return -(g @ phi[:n] + rest @ phi[n:]) / rate

    def field_rows(self, t: float, y, m, z) -> np.ndarray:
        """The field at (t, y) in the tangent's rows: the states', zero past them."""
        out = np.zeros(len(self._phi))
        out[:self.n] = self.value("rhs", self.c, t, y, m, z)
        return out

    def map_at(self, matrix: np.ndarray, moved=None) -> None:
        """A map of the tangent's variables with Jacobian `matrix` applied at an
        instant: Phi <- matrix Phi; at an instant the values move by dt/dp, `moved` =
        (dt/dp, F-, F+[, M_t]) with the fields before and after it and the map's own
        rate in TIME in the tangent's rows, Phi <- matrix (Phi + F- dt/dp) + (M_t -
        F+) dt/dp: the map applies to the state as the instant moves it, at the moved
        TIME, and the field after it runs the shift back (a reset, a section a
        crossing runs, a memory updated where a switch moves)."""
        phi = self.phi
        if moved is None:
            self._phi = matrix @ phi
            return
        shift, before, after, *rate = moved
        drift = after - rate[0] if rate else after
        self._phi = matrix @ (phi + np.outer(before, shift)) - np.outer(drift, shift)

    def _reset(self, t: float, y_prev: np.ndarray, y: np.ndarray, m_prev, m, z_prev, z
               ) -> None:
        """A switch that resets states (MODINT: y+ = R(y-, p), the IC): at an
        instant t_e(p) the values move, y+ = R(y-(t_e), p), so the tangent after it
        is S+ = R_y (S- + f- dt/dp) + R_p - f+ dt/dp, dt/dp = -(n . S- + ds/dp)/rate
        (R_y and R_p by differences of the reset: the IC of a variant), f+ the field
        in every branch changed at the instant. The switches whose surfaces are at
        zero there cross together (MODINT's X1 and X2 written as TR - X and X - TR:
        one instant); the others the reset carried across (a switch on the state it
        resets: its surface apart from zero before and after, on its new branch's
        side) change at that instant too. The memory unchanged; else it says so."""
        n = self.n
        changed = [k for k in range(len(m)) if m[k] != m_prev[k]]
        zero = 1e-9 * (1.0 + float(np.abs(y_prev).max(initial=0.0)))
        e = self.c.surf(t, y_prev.tolist(), m_prev, z_prev)
        crossing = [k for k in changed if abs(e[k]) <= zero]
        resetting = list(m)
        if not changed:
            # (turned straight back: the reset was taken with its switch at zero)
            crossing = [k for k in sorted(self.watch.reset_surfaces) if abs(e[k]) <= zero]
            for k in crossing:
                resetting[k] = 0.0
        # (a PULSE train turning here -- its end at the reset's instant -- is there by
        # its own instant, which moves as its train does)
        trains = [k for k in changed if self.watch.watched[k].surface in self.c.train_surfaces]
        crossing = [k for k in crossing if k not in trains]
        landed = self.c.surf(t, y.tolist(), m, z)
        if not (crossing or trains) or sliding_in(m) or sliding_in(m_prev) or any(
                k in self.watch.levels or not landed[k] * m[k] > zero
                for k in changed if k not in crossing and k not in trains):
            self.failed = "a state is reset with other changes at the instant"
            return
        rest = self._by_data("surf", t, y_prev, m_prev, z_prev)
        shifts = []
        for k in crossing:
            jump = self._jump(k, t, y_prev, m_prev, m, z_prev, z_prev)
            if jump is None:
                return
            g, _, rate = jump
            shifts.append(np.zeros(self.phi.shape[1]) if rate is None else
                          self.shift_of(g, rest[k], rate))
        for k in trains:
            shifts.append(self._train_shift(t, self.watch.watched[k].surface)
                          if self.variants else np.zeros(self.phi.shape[1]))
        shift = shifts[0]
        if any(other is None for other in shifts) or any(
                not np.allclose(other, shift, rtol=1e-6,
                                atol=1e-9 * float(np.abs(shift).max(initial=1.0)))
                for other in shifts[1:]):
            self.failed = "a state is reset where two switches cross that a data value moves apart"
            return
        before = self.field_rows(t, y_prev, m_prev, z_prev)
        if z != z_prev and not self._memory_at_reset(t, y_prev, m_prev, m, z_prev, z, shift,
                                                     before):
            return
        watch, yl = self.watch, y_prev.copy()

        def reset(w, v: np.ndarray) -> np.ndarray:
            return np.asarray(w.apply_resets(v, list(resetting)), dtype=float)

        r_y = np.empty((n, n))
        for j in range(n):
            h = STEP * max(abs(yl[j]), float(self.floor[j]))
            up, down = yl.copy(), yl.copy()
            up[j] += h
            down[j] -= h
            r_y[:, j] = (reset(watch, up) - reset(watch, down)) / (2.0 * h)
        r_p = np.column_stack([
            (reset(watch_of(watch, plus), yl) - reset(watch_of(watch, minus), yl)) / (2.0 * h)
            for plus, minus, h in self.variants]) if self.variants else np.zeros((n, 0))
        size, q = len(self._phi), len(self.variants)
        matrix = np.eye(size)
        matrix[:n, :n] = r_y
        matrix[:n, size - q:] = r_p
        self.map_at(matrix, (shift, before, self.field_rows(t, y, m, z)))

    def _memory_at_reset(self, t: float, y_prev: np.ndarray, m_prev, m, z_prev, z,
                         shift: np.ndarray, before: np.ndarray) -> bool:
        """The memory updated at a reset's instant, before the reset (as the run does
        it: the update reads the states the instant found); False (`failed` said)
        where the tangent does not carry the memory (`ProgramTangent` does)."""
        self.failed = "a state is reset with a memory change at the instant"
        return False

    def _saltation(self, k: int, t: float, y: np.ndarray, before, after, z_before, z_after
                   ) -> np.ndarray | None:
        n = self.n
        jump = self._jump(k, t, y, before, after, z_before, z_after)
        if jump is None:
            return None
        g, diff, rate = jump
        rest = self._by_data("surf", t, y, before, z_before)[k]
        out = np.eye(len(self._phi))
        if rate is None:
            if np.any(rest):  # (a train's instant a data value moves)
                shift = self._train_shift(t, self.watch.watched[k].surface)
                if shift is None:
                    self.failed = "a PULSE train whose instants depend on a data value"
                    return None
                # the later the switch, the longer the old field runs: (f- - f+) dt/dp
                out[:n, len(out) - len(shift):] = -np.outer(diff, shift)
                if self._shift is None:
                    self._shift = shift
                self._turn_shifts.append((shift, bool(np.any(diff))))
            return out
        shift = self.shift_of(g, rest, rate)
        if self._shift is None:  # (d t/d p of the instant: a memory updated there)
            self._shift = shift
        # (a turn that leaves the field as it was bends nothing where a sample is taken)
        self._turn_shifts.append((shift, bool(np.any(diff))))
        # the augmented states' jump: I + (f+ - f-, 0) (ds/dy, ds/d(rest))^T / rate
        out[:n, :n] += np.outer(diff, g) / rate
        out[:n, n:] = np.outer(diff, rest) / rate
        return out

    def _trains_apart(self, t: float, y: np.ndarray, m_prev, m, z) -> bool:
        """Whether the PULSE trains that turn at t can be followed one by one (each
        jumps the tangent by its own (f- - f+) dT/dp, `_saltation`; trains a value
        moves apart, in either order: `_in_any_order`): not where one pulse ends as
        the next starts (PULSE(TZ, P, W) with W = P) and a value moves the two apart:
        the switch does not turn, but a gap or an overlap opens on one side of the
        value only, which `failed` says."""
        if self.variants and self.c.trains:
            for surface in self.c.train_surfaces:
                if self._train_instants(t, surface) > 1 and \
                        self._train_shift(t, surface) is None:
                    self.failed = ("a PULSE ends where the next starts, and a data value "
                                   "moves the two apart: its derivative differs from "
                                   "either side")
                    return False
        return True

    def _train_instants(self, t: float, surface: int) -> int:
        """How many of the trains that turn `surface` have an instant at t."""
        count = 0
        for i, (first, period) in enumerate(self.c.trains):
            if surface in self.c.train_owners[i]:
                k = round((t - first) / period) if period > 0 else 0
                count += k >= 0 and abs(first + k * period - t) <= 1e-12 * max(abs(t), 1.0)
        return count

    def _train_shift(self, t: float, surface: int) -> np.ndarray | None:
        """d t/d p of the instant at t of the trains that turn `surface` (a PULSE
        train's start or end, first + k period: `ModelCode.trains`), from the same
        instant of the variants' trains; None if none has an instant at t, or two
        that move differently do."""
        found = None
        for i, (first, period) in enumerate(self.c.trains):
            if surface not in self.c.train_owners[i]:
                continue
            k = round((t - first) / period) if period > 0 else 0
            if k < 0 or abs(first + k * period - t) > 1e-12 * max(abs(t), 1.0):
                continue
            shift = np.array([((plus.trains[i][0] + k * plus.trains[i][1]) -
                               (minus.trains[i][0] + k * minus.trains[i][1])) / (2.0 * h)
                              for plus, minus, h in self.variants])
            if found is not None and not np.allclose(found, shift, rtol=1e-9, atol=1e-12):
                return None
            found = shift
        return found


@dataclass
class _Path:
    """The updates a restart made to the memory: (modes before, modes after) each,
    and the memory triggers crossed and taken back at once."""

    steps: list[tuple[list[float], list[float]]]
    returned: list[int]


GROUP = 4  # slots tested one by one below this many (`read_slots`)


def _moved_together(z, slots: list[int]) -> list:
    """z with each of `slots` moved by its own odd fraction of STEP of its size (no two
    moves cancel where a function reads several)."""
    moved = list(z)
    for i, j in enumerate(slots):
        moved[j] = z[j] + STEP * max(abs(z[j]), 1.0) * (1.0 + 0.618034 * (i % 7))
    return moved


def read_slots(f, centre: np.ndarray, z, slots: list[int]) -> list[int]:
    """Which of `slots` f(z) moves with: sets of them moved together (each by its own
    odd fraction of STEP, so that no two cancel), a set that moves nothing dropped
    whole, the others halved (DELAY's store: its read takes two of a hundred samples;
    a difference of each was most of a tangent's time)."""
    if len(slots) <= GROUP:
        return slots
    if np.array_equal(np.asarray(f(_moved_together(z, slots)), dtype=float), centre):
        return []
    half = len(slots) // 2
    return read_slots(f, centre, z, slots[:half]) + read_slots(f, centre, z, slots[half:])


def copied_slots(f, centre: np.ndarray, z, slots: list[int]) -> list[int]:
    """Which of `slots` the memory map f(z) copies as they are (its column e_j): sets
    of them moved together (`read_slots`' way), a set whose moved values come out
    unchanged, the rest as before, kept whole; the others halved."""
    if not slots:
        return []
    moved = _moved_together(z, slots)
    out = np.asarray(f(moved), dtype=float)
    expect = centre.copy()
    expect[slots] = [moved[j] for j in slots]
    if np.array_equal(out, expect):
        return slots
    if len(slots) == 1:
        return []
    half = len(slots) // 2
    return copied_slots(f, centre, z, slots[:half]) + copied_slots(f, centre, z, slots[half:])


def has_slope(c, z, j: int) -> bool:
    """Whether what reads memory slot j has a slope in it: not an instant not yet set
    (-INF), nor an instant the model switches at, whose only effect is that switch's
    jump (`ProgramTangent._wake`), nor an instant or count a store keeps
    (`ModelCode.clock_slots`: where a free delay moves them, they move with it,
    `along_clock`)."""
    return math.isfinite(z[j]) and j not in c.wake_slots and j not in c.clock_slots


def along_clock(f, base, variants, halves, z, clock: np.ndarray, rows: np.ndarray
                ) -> np.ndarray:
    """d f/d p (f(code, z): a column per value) where a free delay moves a store's
    instants: each value's variants (`base`'s functions bound to p +- h) read the
    store with its clock slots moved along their rows of the tangent (`rows`: those
    slots x values), as a run with the value moved keeps them -- moved alone, the
    store's start and its oldest sample part. With `halves` (the same bound to p +-
    h/2), on the branch the point is on where one side crosses a kink within h (a
    read that leaves the held start at TIME = t0 + P: `along_branch`)."""
    cols = []
    for j, (plus, minus, h) in enumerate(variants):
        codes = {0.0: base, h: plus, -h: minus}
        if halves:
            codes[0.5 * h], codes[-0.5 * h] = halves[j]

        def at_step(d: float, j=j, codes=codes) -> np.ndarray:
            v = list(z)
            for k, r in zip(clock.tolist(), rows[:, j].tolist(), strict=True):
                if r and math.isfinite(z[k]):
                    v[k] = z[k] + d * r
            return np.asarray(f(codes[d], v), dtype=float)

        cols.append(along_branch(at_step, h) if halves else
                    (at_step(h) - at_step(-h)) / (2.0 * h))
    return np.array(cols).T


SAMPLED_AT_TURN = ("a DELAY samples where a switch turns, at an instant a data value moves "
                   "apart from it: its derivative differs from either side")


class ProgramTangent(ParameterTangent):
    """`ParameterTangent` of a program in ACSL form: the states y (n) augmented by the
    r memory values z its DISCRETE and DYNAMIC code keep (constant between the
    program's instants, z' = 0) and by the q data values p: the matrix is
    [[A, F_z, F_p], [0, 0, 0], [0, 0, 0]], F_z = d f/d z by central differences
    (h = STEP max(|z|, 1)); a switch's jump takes the surface's dependence on z in;
    the code an instant runs is a map of (y, z) whose Jacobian `jump` applies
    (`analysis.program` takes it). `start` = d (y, z)(t0) / d p."""

    def __init__(self, c, watch, floor: np.ndarray, start: np.ndarray,
                 variants: list[tuple[object, object, float]], memory: int,
                 outputs: list[int] | None = None, exact: np.ndarray | None = None) -> None:
        super().__init__(c, watch, floor, start, variants, outputs, exact)
        self.n, self.r = start.shape[0] - memory, memory
        self._moving = self.n
        # (the memory a step was given, as its samples inside left it, up to when)
        self._sampled: tuple[list, list, float] | None = None
        # the slots that hold a sampling memory's next instant (DELAY's store)
        from ..library import lookup

        specs = [(mem, lookup(mem.func, len(mem.args)).memory)
                 for mem in (c.model.memories if c.model is not None else ())]
        # each sampling store's next-instant slot, and the slots the store keeps
        self._stores = {mem.slot + spec.samples: range(mem.slot, mem.slot + mem.nslots)
                        for mem, spec in specs if spec.samples is not None}
        self._next_slots = list(self._stores)
        # whether a store's instants move with the values (a free delay): then its
        # clock slots are carried like the others (`clock_moves`)
        self._clock = np.array(sorted(c.clock_slots), dtype=int)
        self._clock_moves = False
        # the last instant a store sampled at, and its d t/d p
        self._sampled_at: tuple[float, np.ndarray | None] = (-math.inf, None)
        # () -> the variants' functions bound to p +- h/2, (plus, minus) per value, where
        # the caller has them (`along_clock`; built when a store's clock first moves)
        self.make_halves: Callable[[], list[tuple[object, object]]] | None = None
        self._halves: list[tuple[object, object]] | None = None

    @property
    def halves(self) -> list[tuple[object, object]] | None:
        if self._halves is None and self.make_halves is not None:
            self._halves = self.make_halves()
        return self._halves

    def clock_moves(self) -> bool:
        """Whether a store's instants and counts have a slope in the values (its
        spacing P/N, a free delay's, set at its start): from then on every map and
        read is differenced in them too, and the store samples at instants that
        move (`__call__`)."""
        if not self._clock_moves and len(self._clock):
            self._clock_moves = bool(np.any(self._phi[self.n + self._clock]))
        return self._clock_moves

    def _memory_moved(self, t: float, y: np.ndarray, m_prev, m, z_prev, z) -> bool:
        return True

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        """A step [ta, tb] given the memory it started with: where memory samples the
        trajectory inside it (DELAY's store, at the instants it asks for), the tangent
        is cut there and the sample's map applied, as the run's loop samples from the
        dense output (a later piece of the same step goes on from the samples taken)."""
        c = self.c
        if c.next_sample is None:
            return self._between(ta, tb, interp, m, z)
        given = list(z)
        if self._sampled is not None and self._sampled[0] == given and \
                ta >= self._sampled[2]:
            z = self._sampled[1]
        t, g = ta, c.next_sample(z)
        # (where a free delay moves the store's instants, one due at the step's end is
        # taken here, at its moving instant: the update at the step's end would take it
        # at that fixed instant on one side of the value only. One a few ulps after it
        # is the next step's, as the run's: taken here, the run's update would not
        # retrace it)
        at_end = self.clock_moves()
        while (g < tb or (at_end and g == tb)) and self.failed is None:
            self._between(t, g, interp, m, z)
            if self.failed is not None:
                return
            y = np.asarray(interp(g), dtype=float)
            before = list(z)
            self._sample_at(g, y, m, before)
            z = list(c.sample(g, y.tolist(), m, before))
            self.prev, self._lean = (g, y, list(m), list(z)), None
            after = c.next_sample(z)
            if not after > g:
                break
            t, g = g, after
        self._between(t, tb, interp, m, z)
        self._sampled = (given, list(z), tb)

    def _between(self, ta: float, tb: float, interp, m, z) -> None:
        """[ta, tb] with no sample inside, cut where a delayed value passes a stored
        point (`ModelCode.read_knots`): the values' part of the field jumps there (d XD
        /d TDL is minus the history's slope, which changes at each sample), and a step
        across it loses the quadrature's order -- 3e-6 of d X/d TDL at RELERR 1e-9,
        ACSL's DELAY sampling every DMIN, which TDL is no multiple of."""
        knots = self.c.read_knots(z, ta, tb) if self.c.read_knots is not None else ()
        t = ta
        for u in knots:
            super().__call__(t, u, interp, m, z)
            if self.failed is not None:
                return
            t = u
        super().__call__(t, tb, interp, m, z)

    def _sample_at(self, g: float, y: np.ndarray, m, z) -> None:
        """A store samples the trajectory at g (its next instant, slot `_next_slots`):
        the sample's map applies; where a free delay moves g (that slot's row, dg/dp),
        at the moved instant: J (Phi + f- dg) + (M_t - f+) dg, M_t the map's rate in
        TIME on the side the sample is taken (t >= g), where the stored value and the
        newest point's instant move with it."""
        n, yl = self.n, y.tolist()

        def sample(code, tt, yv, zv):
            return code.sample(tt, yv, m, zv)

        moves = self.clock_moves()
        due = [self.phi[n + k] for k in self._next_slots if z[k] == g] if moves else []
        shift = due[0].copy() if due else np.zeros(len(self.variants))
        if any(not np.allclose(other, shift, rtol=1e-9, atol=1e-12) for other in due[1:]):
            self._apart(g, y, m, z)
            return
        if not moves:
            self._sampled_at = (g, shift)
            if self._turn_apart():
                self.map_at(self._memory_map(sample, g, yl, z))
            return
        self._moving_sample(sample, g, y, m, z, shift)

    def _apart(self, g: float, y: np.ndarray, m, z) -> None:
        """Stores that sample at g, at instants a data value moves apart (two delays
        of X written as two values that are equal, TDL = TDL2): each store's sample
        reads the states and its own slots alone, so they are taken one by one, each
        at its own moving instant."""
        for k in [k for k in self._next_slots if z[k] == g]:
            slots = self._stores[k]

            def alone(code, tt, yv, zv, slots=slots):
                new = code.sample(tt, yv, m, zv)
                return [new[i] if i in slots else v for i, v in enumerate(zv)]

            z = self._moving_sample(alone, g, y, m, z, self.phi[self.n + k].copy())
            if z is None:
                return

    def _moving_sample(self, call, g: float, y: np.ndarray, m, z, shift: np.ndarray
                       ) -> list | None:
        """The sample z' = call(code, g, y, z) taken at g as it moves by `shift`
        (`_along`), the fields either side of it in the tangent's rows; z' (None, and
        `failed` said, where a switch turning at g moves apart from it)."""
        self._sampled_at = (g, shift)
        if not self._turn_apart():
            return None
        yl = y.tolist()
        after = list(call(self.c, g, yl, list(z)))
        self._along(call, g, y, z, shift, self.field_rows(g, yl, m, z),
                    self.field_rows(g, yl, m, after))
        return after

    def _samples_move_with(self, t: float, z_prev) -> bool:
        """Whether the samples a store's update takes at t -- those due there, at a
        step's end; the loop takes the others from the dense output -- move with the
        instant (`_shift`, where a switch turns): a sample at DMIN's fixed spacing due
        where ACSL's DELAY turns from IC to the history, TDL free, is taken before the
        turn on one side of the value and after it on the other."""
        q = len(self.variants)
        shifts = [*(shift for shift, bends in self._turn_shifts if bends),
                  *([self._shift] if self._shift is not None else [])]
        if not any(np.any(shift) for shift in shifts):
            return True
        for k in self._next_slots:
            if z_prev[k] <= t:
                own = self.phi[self.n + k] if self.clock_moves() else np.zeros(q)
                if not all(np.allclose(own, shift, rtol=1e-9, atol=1e-12)
                           for shift in shifts):
                    self.failed = SAMPLED_AT_TURN
                    return False
        return True

    def _turn_apart(self) -> bool:
        # (a sample where a switch turns takes the field's one side or the other as a
        # value moves the two apart: no derivative -- a STEP(0.3) at the 6th sample of
        # P/20, P free. Moved together -- ACSL's DELAY turning from IC to the history
        # at its NMX-th sample, both at TDL -- the sample and the switch's jump are
        # one map at one moving instant, and compose)
        (t, turns), (g, sample) = self._turned, self._sampled_at
        if not math.isfinite(t) or abs(t - g) > 4 * np.finfo(float).eps * max(abs(t), 1.0):
            return True
        q = len(self.variants)
        # (every switch that turns there: ACSL's DELAY turning with its sample, and a
        # STEP at TDL that stays put, bends X where the sample is taken)
        if all(np.allclose(turn, sample, rtol=1e-9, atol=1e-12)
               for turn in turns or [np.zeros(q)]):
            return True
        self.failed = SAMPLED_AT_TURN
        return False

    def _along(self, call, t: float, y: np.ndarray, z, shift: np.ndarray,
               before: np.ndarray, after: np.ndarray) -> None:
        """A memory map z' = call(code, t, y, z) at an instant that moves by `shift`
        (dt/dp) applied where a store's clock moves: each column of the tangent is the
        map's central difference along that column's own direction -- TIME by dt/dp,
        the states by S + f- dt/dp, the memory by its rows, the value by its variant's
        step -- so that the spacing slot and the spacing the call asks for (P/N) move
        together, as in a run with the value moved (moved apart, the store would
        start a new spacing: a jump); the states' rows take (f- - f+) dt/dp."""
        n, r = self.n, self.r
        phi = self.phi.copy()
        centre = np.asarray(call(self.c, t, y.tolist(), list(z)), dtype=float)
        for j, (plus, minus, h) in enumerate(self.variants):
            dy = phi[:n, j] + before[:n] * shift[j]
            dz = np.nan_to_num(phi[n:n + r, j], nan=0.0, posinf=0.0, neginf=0.0)
            ends = []
            for code, sign in ((plus, 1.0), (minus, -1.0)):
                zv = [v + sign * h * d if d else v for v, d in zip(z, dz.tolist(), strict=True)]
                moved = t + sign * h * shift[j]
                for k in self._next_slots:
                    # (a store due at the instant and moving with it samples at it
                    # moved: its own row, equal to the instant's but for rounding, put
                    # its next sample an ulp to one side -- a second store sampling
                    # with the first, on a spacing twice as long, skipped it or took
                    # it twice)
                    if z[k] == t and abs(dz[k] - shift[j]) <= \
                            1e-9 * abs(shift[j]) + 1e-12:
                        zv[k] = moved
                ends.append(np.asarray(call(code, moved, (y + sign * h * dy).tolist(), zv),
                                       dtype=float))
            # (the side whose store took the same samples as the run's: a sample due
            # within the step of the instant is taken on one side only)
            with np.errstate(invalid="ignore"):
                phi[n:n + r, j] = np.nan_to_num(one_sided((ends[0] - centre) / h,
                                                          (centre - ends[1]) / h))
        phi[:n] += np.outer(before[:n] - after[:n], shift)
        self._phi = phi

    def _memory_map(self, call, t: float, yl: list, z) -> np.ndarray:
        """The Jacobian of a memory map z' = call(code, t, y, z) as a map of the
        tangent's variables: its rows for z (d/dy and d/dz on the branch the point is
        on, d/dp on the side that does not bend), the states and values kept."""
        n, r, c = self.n, self.r, self.c
        size, q = len(self._phi), len(self.variants)
        matrix = np.eye(size)
        matrix[n:n + r, n:n + r] = 0.0
        for j in range(n):
            h = STEP * max(abs(yl[j]), float(self.floor[j]))
            matrix[n:n + r, j] = branch_difference(lambda v: call(c, t, v, z), yl, j, h)
        centre = np.asarray(call(c, t, yl, z), dtype=float)

        def by_z(v):
            return call(c, t, yl, v)

        # (PULSE's -INF before a first trigger; a store's instants and counts; the
        # slots the map copies as they are, most of a store's)
        slots = [j for j in range(r) if math.isfinite(z[j]) and j not in c.clock_slots]
        copied = set(copied_slots(by_z, centre, z, slots))
        for j in slots:
            if j in copied:
                matrix[n + j, n + j] = 1.0
                continue
            matrix[n:n + r, n + j] = branch_difference(by_z, list(z), j,
                                                       STEP * max(abs(z[j]), 1.0))
        for j, (plus, minus, h) in enumerate(self.variants):
            matrix[n:n + r, size - q + j] = one_sided(
                (np.asarray(call(plus, t, yl, z), dtype=float) - centre) / h,
                (centre - np.asarray(call(minus, t, yl, z), dtype=float)) / h)
        return matrix

    def leaned(self, t: float, y: np.ndarray, m, z) -> list:
        """z with each play's memory (HSTRSS, BCKLSH) that the motion from (t, y) pushes
        moved into the clamp, by far more than a difference's step (LEAN of it): the
        play's value is the clamp's edge either way, and its derivatives are then the
        branch the motion is on, following the input (d/dz 0, d/dX 1). At z itself --
        the clamp's kink, where every update leaves a play that follows -- central
        differences gave half of each. A play the motion does not push holds (z as
        it is)."""
        if self._sampled is not None and list(z) == self._sampled[0]:
            z = self._sampled[1]  # (a row inside a step the store sampled in)
        slots = self.c.play_slots
        if not slots:
            return z
        yl = [float(v) for v in y]
        h = self.watch.lookahead_h
        f = np.asarray(self.value("rhs", self.c, t, yl, m, z), dtype=float)
        ahead = self.c.mem(t + h, (np.asarray(yl) + h * f).tolist(), m, m, list(z))
        out = list(z)
        for j in slots:
            if ahead[j] != z[j] and math.isfinite(z[j]):
                out[j] = z[j] - math.copysign(LEAN * max(abs(z[j]), 1.0), ahead[j] - z[j])
        return out

    def engaged(self, ta: float, tb: float, interp, m, z, zl) -> float | None:
        """The first instant in (ta, tb) at which a play that holds at ta (z as it is in
        `zl`) has started to move, to a few ulps (bisection on whether its value has
        left z: before it, the clamp holds z exactly)."""
        held = [j for j in self.c.play_slots if zl[j] == z[j] and math.isfinite(z[j])]
        if not held:
            return None

        def moved(t: float) -> bool:
            y = np.asarray(interp(t), dtype=float).tolist()
            v = self.c.mem(t, y, m, m, list(z))
            return any(v[j] != z[j] for j in held)

        if not moved(tb):
            return None
        lo, hi = ta, tb
        while hi - lo > 4 * np.finfo(float).eps * max(abs(hi), 1.0):
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            lo, hi = (lo, mid) if moved(mid) else (mid, hi)
        return hi if hi < tb else None

    def _memory_at_reset(self, t: float, y_prev: np.ndarray, m_prev, m, z_prev, z,
                         shift: np.ndarray, before: np.ndarray) -> bool:
        self._shift = shift
        self._update_memory(t, y_prev, m_prev, m, z_prev, z, before)
        return self.failed is None

    def _update_memory(self, t: float, y: np.ndarray, m_prev, m, z_prev, z,
                       field: np.ndarray | None = None) -> None:
        """The memory functions' update at t, z = mem(t, y, m_prev, m, z_prev) (every
        step's end, a located switch): its Jacobian in y, z, p and TIME (central
        differences of the generated update) applies to the memory rows, with y's
        total derivative S + f dt/dp where the instant moves (a ZHOLD that holds
        where its trigger crosses: dZ/dp = dB/dp + dB/dt dt/dp); f is `field` in the
        tangent's rows where given (the field before a reset that follows the update:
        S is still the one before the instant), else the field after the instant (S
        after its switches' jumps: the same total)."""
        n, r, c = self.n, self.r, self.c
        yl, m_prev, m = np.asarray(y, dtype=float).tolist(), list(m_prev), list(m)
        path = self._update_path(t, yl, m_prev, m, z_prev, z)
        if path is None:
            self.failed = "the memory changes at an instant the tangent cannot retrace"
            return
        if not self._samples_move_with(t, z_prev):
            return
        for k in path.returned:
            # a trigger crossed and taken back at once (the run's `returning`): the
            # modes are as they were, the memory and so the field are not, at an
            # instant the values move -- that switch's jump
            s = self._saltation(k, t, y, m_prev, m, z_prev, z)
            if s is None:
                return
            self._phi = s @ self.phi

        def update(code, tt: float, yv: list, zv: list) -> np.ndarray:
            for before, after in path.steps:
                zv = code.mem(tt, yv, before, after, list(zv))
            return np.asarray(zv, dtype=float)

        if self.clock_moves():
            shift = self._shift if self._shift is not None else np.zeros(len(self.variants))
            if field is None:
                field = self.field_rows(t, yl, m, z)
            self._along(update, t, np.asarray(yl), z_prev, shift, field, field)
            return
        # (an update reads a trigger's sign where its mode is not positive, a sign that
        # jumps at the crossing it may be taken at: `branch_difference` keeps to the
        # branch the run's update took; the same sign moved by a value, `one_sided`)
        matrix = self._memory_map(update, t, yl, z_prev)
        size = len(self._phi)
        shift = self._shift
        if shift is None or not np.any(shift):
            self.map_at(matrix)
            return
        # (y's total derivative where the instant moves, and the update's own rate)
        ht = STEP * max(abs(t), 1.0)
        rate = np.zeros(size)
        rate[n:n + r] = (update(c, t + ht, yl, z_prev) - update(c, t - ht, yl, z_prev)) / \
            (2.0 * ht)
        if field is None:
            field = self.field_rows(t, yl, m, z)
        self.map_at(matrix, (shift, field, field, rate))

    def _wake(self, t: float, y: np.ndarray, m, z) -> None:
        """An instant a memory slot holds reached at t (CSMP's PULSE(P, X) ending at
        the trigger's instant + P): the field changes there with TIME alone, at an
        instant that moves as the slot does, dt/dp = its row of the tangent: the jump
        (f- - f+) dt/dp, f- the field a few ulps before t."""
        due = [s for s in self.c.wake_slots
               if abs(z[s] - t) <= 4 * np.finfo(float).eps * max(abs(t), 1.0)]
        if not due:
            return
        before = float(np.nextafter(np.nextafter(t, -np.inf), -np.inf))
        f_minus, f_plus = self.field_rows(before, y, m, z), self.field_rows(t, y, m, z)
        if np.array_equal(f_minus, f_plus):
            return
        self.map_at(np.eye(len(self._phi)), (self.phi[self.n + due[0]].copy(), f_minus, f_plus))

    def _update_path(self, t: float, yl: list, m_prev, m, z_prev, z) -> _Path | None:
        """How the run's restart took the memory from z_prev to z: one update (m_prev
        to m), or, where a memory trigger at zero was crossed and taken back at once
        (the modes as they were), the update to the crossed modes and back; None if
        neither gives z."""
        now = np.asarray(z, dtype=float)
        close = 1e-12 * (1.0 + float(np.max(np.abs(now), initial=0.0)))

        def gives(steps) -> bool:
            zv = list(z_prev)
            for before, after in steps:
                zv = self.c.mem(t, yl, before, after, zv)
            return bool(np.allclose(zv, now, rtol=1e-9, atol=close))

        # (a trigger standing at zero with its mode as it was: crossed and taken back,
        # the update the crossed mode decides -- before it, the update read the
        # trigger's sign, which its rounding decides there)
        e = self.c.surf(t, yl, m_prev, list(z_prev))
        for k in self.watch.memory_triggers if self.watch is not None else ():
            if m_prev[k] not in (1.0, -1.0) or m[k] != m_prev[k] or \
                    abs(e[k]) > 1e-9 * (1.0 + abs(e[k])):
                continue
            crossed = list(m_prev)
            crossed[k] = -m_prev[k]
            # (the update the crossed mode decides alone -- RST's, read from M -- or
            # the two the run made -- PULSE's, read from the new modes N)
            for steps in ([(crossed, m)], [(m_prev, crossed), (crossed, m)]):
                if gives(steps):
                    return _Path(steps, [k])
        if gives([(m_prev, m)]):
            return _Path([(m_prev, m)], [])
        return None

    def _by_z(self, fn: str, t: float, y: np.ndarray, m, z) -> np.ndarray:
        """d fn(t, y, m, z) / d z, a column per memory value: nonzero only for the
        slots fn reads here (`read_slots`), each on the branch the point is on (a
        play held within a step of its clamp's kink, just after it turned, reads its
        memory whole)."""
        yl = np.asarray(y, dtype=float).tolist()

        def f(v):
            return self.value(fn, self.c, t, yl, m, v)

        centre = np.asarray(f(z), dtype=float)
        out = np.zeros((len(centre), self.r))
        # (the branch matters at a play's clamp only, the one kink in z between instants)
        difference = branch_difference if self.c.play_slots else central_difference
        for j in read_slots(f, centre, z, [j for j in range(self.r)
                                           if has_slope(self.c, z, j)]):
            out[:, j] = difference(f, list(z), j, STEP * max(abs(z[j]), 1.0))
        return out

    def _by_data(self, fn: str, t: float, y: np.ndarray, m, z) -> np.ndarray:
        """d fn / d (z, p): the memory values' columns, then the data values' (with
        a store's clock moved along, where a free delay moves it: `along_clock`)."""
        if self.clock_moves():
            yl = np.asarray(y, dtype=float).tolist()
            by_p = along_clock(lambda code, v: self.value(fn, code, t, yl, m, v), self.c,
                               self.variants, self.halves, z, self._clock,
                               self._phi[self.n + self._clock, :])
        else:
            by_p = super()._by_data(fn, t, y, m, z)
        return np.hstack([self._by_z(fn, t, y, m, z), by_p]) if self.r else by_p

    def jump(self, matrix: np.ndarray, t: float, y: np.ndarray, m, z, moved=None) -> None:
        """The code of an instant at t ran: its Jacobian (of (y, z, p), identity rows
        for p) applies (at an instant the values move: `moved`, as `map_at` takes it),
        and the next step starts from what it left."""
        self.map_at(matrix, moved)
        self.prev = (t, np.asarray(y, dtype=float).copy(), list(m), list(z))
