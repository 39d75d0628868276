"""The surface watch: which branch each watched surface is in, where it changes,
and the motion while surfaces slide.

A `SurfaceWatch` works from explicit inputs only: the generated functions and the
plan's table of watched surfaces (kinds, purposes, gradients, the look-ahead
step). It never steps; the loop hands it states, modes and dense outputs.

- `field`, `outputs`: the vector field and the recorded variables under given
  modes, with sliding surfaces resolved (`slide.py`);
- `choose_modes`: the branches in force from an instant on. A surface at zero
  there goes the way the dynamics take it (`direction`: the sign of its rate in
  each branch); both branches pushing it back to zero means sliding;
- `crossed`, `locate`: whether a step crossed a surface, and where (Brent's
  method on the dense output); `slide_exits`, `locate_slide_exit` likewise for
  the end of a slide;
- `silent`: whether a surface's branch changes the derivatives at all now.
"""

from __future__ import annotations

import math

import numpy as np

from ..codegen import ModelCode
from ..library.surfaces import DOWN, REPELS, SLIDES, STILL, UP, leaving, sign
from .jacobian import STEP
from .plan import LOOKAHEAD, SLIDE, Purpose, RunPlan, SurfaceKind, slides, sliding, sliding_in
from .slide import MAX_SLIDING, combine, corner_modes, side_mode, slide_weights

_EPS = float(np.finfo(float).eps)
_XTOL = 4 * _EPS


class SurfaceWatch:
    def __init__(self, c: ModelCode, plan: RunPlan) -> None:
        self.c = c
        self.plan = plan
        self.watched = plan.watched
        self.resets = plan.resets
        self.lookahead_h = plan.lookahead_h
        self.watch_idx = plan.watch_idx
        self.events = plan.events
        # the level surfaces (QNTZR, NINT, AINT, AMOD): a slide on one is on an edge
        # between two levels (`slide.side_mode`)
        self.levels = frozenset(k for k, w in enumerate(plan.watched)
                                if w.kind is SurfaceKind.LEVEL)
        self.y0 = c.y0
        # the surfaces a memory function switches on (ZHOLD's, RST's triggers): its
        # memory changes as the motion crosses, so the branch the motion is pushed
        # back from is not the field it meets on return (no sliding there)
        triggers = {s for mem in (c.model.memories if c.model is not None else ())
                    for s in mem.surfaces}
        self.memory_triggers = {k for k, w in enumerate(plan.watched) if w.surface in triggers}
        # the surfaces a state reset reads (MODINT's X1, X2): held or reset, the
        # derivative is 0 either way, but the state is put back where one flips
        self.reset_surfaces = {k for r in self.resets for k in (r.first, r.second)
                               if isinstance(k, int)}
        # (modes, sliding surfaces) -> the surfaces whose value is a sliding switch's
        # (RSW(X > 0.5, ...) while X - 0.5 slides): their sides differ corner to corner
        self._followers: dict[tuple, list[int]] = {}

    # ------------------------------------------------------------ vector fields
    sliding = staticmethod(sliding)

    def field(self, t: float, y: np.ndarray, m, z) -> np.ndarray:
        """The derivatives under modes m; sliding surfaces take the Filippov
        combination of their branches that keeps them at zero."""
        if not sliding_in(m):
            return self.c.rhs(t, y.tolist(), m, z)
        modes, fields, weights = self._mix(t, y, m, z, self.sliding(m))
        return combine(weights, fields)

    def outputs(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """The recorded variables, weighted like the field while surfaces slide."""
        if not sliding_in(m):
            return self.c.out(t, y.tolist(), m, z)
        modes, _, weights = self._mix(t, y, m, z, self.sliding(m))
        columns = [np.asarray(self.c.out(t, y.tolist(), mc, z), dtype=float) for mc in modes]
        return combine(weights, columns).tolist()

    def as_they_are(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """Modes m with each sign surface that is not sliding on the side it is on at
        (t, y): inside a step the loop follows a silent surface's sign only at the
        step's end (a switch only printed, ABS(SIN(3 T) - 0.2)), and a value read
        between (RANGE's) took the other branch: -0.799 for an ABS (hunt 53)."""
        try:
            lit = self.c.modes_literal(t, y.tolist(), m, z)
        except (ArithmeticError, ValueError):
            return m
        out = list(m)
        for k, w in enumerate(self.watched):
            if w.kind is SurfaceKind.SIGN and lit[k] != 0.0 and lit[k] != m[k] and \
                    not slides(m[k]):
                out[k] = lit[k]
        return out

    def standing(self, ts: np.ndarray, ys: np.ndarray, m, z) -> list | None:
        """`as_they_are` over many instants of one branch (rows ys at ts): modes m with
        each silent sign surface that has crossed a column of its own signs (zero
        where it is zero: the X = 0 branch, as a row there shows); None when a
        surface the loop must locate has crossed (the samples' values then need the
        loop's way)."""
        with np.errstate(all="ignore"):
            surfaces = [np.broadcast_to(np.asarray(e, float), ts.shape)
                        for e in self.c.surf_v(ts, list(ys.T), m, z)]
        modes: list = list(m)
        for k, mask in crossings(self.plan, surfaces, m).items():
            i = int(np.argmax(mask))
            if self.watched[k].kind is not SurfaceKind.SIGN or \
                    not self.silent(k, float(ts[i]), ys[i], m, z):
                return None
            modes[k] = np.sign(surfaces[k])
        return modes

    def _mix(self, t, y, m, z, ks, with_rates: bool = False):
        """The corners (every sliding surface of `ks` in either branch), their fields,
        and the weight of each corner (and the sliding surfaces' rates at each)."""
        if len(ks) > MAX_SLIDING:
            raise TooManySlides(len(ks))
        yl = y.tolist()
        modes = self.corners(t, y, m, z, ks)
        fields = [np.asarray(self.c.rhs(t, yl, mc, z), dtype=float) for mc in modes]
        rates = np.array([[self.slide_rate(k, t, y, f, self._rated(k, mc, m), z) for k in ks]
                          for f, mc in zip(fields, modes, strict=True)])
        if with_rates:
            return modes, fields, slide_weights(rates), rates
        return modes, fields, slide_weights(rates)

    def corners(self, t: float, y: np.ndarray, m, z, ks: list[int]) -> list[list[float]]:
        """The corners of the surfaces `ks` sliding in m (`slide.corner_modes`), each
        level's corner with the switches that level's value puts on another side
        there on that side (`follow`)."""
        modes = corner_modes(m, ks, self.levels)
        if any(k in self.levels for k in ks):
            return self.follow(t, y, modes, z)
        return self._with_followers(t, y, m, z, ks, modes)

    def _with_followers(self, t: float, y: np.ndarray, m, z, ks: list[int],
                        corners: list[list[float]]) -> list[list[float]]:
        """The corners of sign surfaces sliding, with each surface whose value is a
        value of theirs (a switch's condition that is a sliding relational test, RSW(X >
        0.5, 1., 0.)) on its side in each corner -- at zero where the test is 0 there,
        which selects the function's own branch at 0. Without it the condition kept
        the side it had when the slide began, and RSW took one branch all along (2.5
        for Filippov's 1.25, hunt 53). Which surfaces follow is found once per slide."""
        key = (tuple(m), tuple(ks))
        deps = self._followers.get(key)
        if deps is not None and not deps:
            return corners
        yl = y.tolist()
        try:
            lits = [self.c.modes_literal(t, yl, b, z) for b in corners]
        except (ArithmeticError, ValueError):
            return corners
        if deps is None:
            deps = [j for j in range(len(m)) if j not in ks and not slides(m[j])
                    and self.watched[j].kind is SurfaceKind.SIGN
                    and len({lit[j] for lit in lits}) > 1]
            if len(self._followers) > 4096:
                self._followers.clear()
            self._followers[key] = deps
        out = [list(b) for b in corners]
        for o, lit in zip(out, lits, strict=True):
            for j in deps:
                o[j] = lit[j]
        return out

    def follow(self, t: float, y: np.ndarray, branches: list[list[float]], z
               ) -> list[list[float]]:
        """`branches` (the corners of level surfaces either side of an edge) with each
        sign surface whose side differs from one to another on its side there in each,
        and each other level function in the level it reads in each: a relay on a
        quantized sensor, FSW(1.2 - QNTZR(1.0, X), ...), is on in the level below the
        edge and off above it; AINT(2.2 - QNTZR(1.0, X)) is 1 below, 0 above.
        Without it, either level read the relay as it was, and neither pushed back
        (the run chattered across the edge)."""
        yl = y.tolist()
        try:
            lits = [self.c.modes_literal(t, yl, b, z) for b in branches]
        except (ArithmeticError, ValueError):
            return [list(b) for b in branches]
        out = [list(b) for b in branches]
        for j, w in enumerate(self.watched):
            values = {lit[j] for lit in lits}
            if len(values) < 2 or any(slides(b[j]) for b in branches) or \
                    len({b[j] for b in branches}) > 1:
                continue  # (the same everywhere, sliding, or itself one of the moved)
            # (a sign at zero there is no side; a level's literal is its level, 0 too)
            if w.kind is SurfaceKind.SIGN and 0.0 in values:
                continue
            if w.kind in (SurfaceKind.SIGN, SurfaceKind.LEVEL):
                for o, lit in zip(out, lits, strict=True):
                    o[j] = lit[j]
        return out

    def branch_rates(self, k: int, t: float, y: np.ndarray, m, z):
        """Both branches of surface k (other sliding surfaces resolved): their vector
        fields f+ and f-, and the surface's rate along each (d+, d-). A level surface
        in m is on the edge it slides on (its mode), its branches the levels either
        side."""
        level = k in self.levels
        mp, mm = list(m), list(m)
        mp[k], mm[k] = side_mode(m[k], 1.0, level), side_mode(m[k], -1.0, level)
        if level:
            mp, mm = self.follow(t, y, [mp, mm], z)
        fp = np.asarray(self.field(t, y, mp, z), dtype=float)
        fm = np.asarray(self.field(t, y, mm, z), dtype=float)
        return (fp, fm, self.surface_rate(k, t, y, fp, self._rated(k, mp, m), z),
                self.surface_rate(k, t, y, fm, self._rated(k, mm, m), z))

    def _rated(self, k: int, branch, m):
        """The modes surface k's rate is read in along a branch's field: the branch's,
        but a level surface's own is the edge in m (in a level, its value is the
        distance to the nearer edge, which is the other way up on either side)."""
        if k not in self.levels:
            return branch
        out = list(branch)
        out[k] = m[k]
        return out

    def surface_rate(self, k: int, t: float, y: np.ndarray, f: np.ndarray, m, z) -> float:
        """d e_k/dt along f: exact for surfaces linear in the states, else a difference
        ahead along f (the way the motion goes from a point on it)."""
        g = self.watched[k].gradient
        if g is not None:
            return float(g @ f)
        h = self.lookahead_h
        e0 = self.c.surf(t, y.tolist(), m, z)[k]
        e1 = self.c.surf(t + h, (y + h * f).tolist(), m, z)[k]
        return (e1 - e0) / h

    def slide_rate(self, k: int, t: float, y: np.ndarray, f: np.ndarray, m, z) -> float:
        """`surface_rate` of a sliding surface, for its weight in the slide's field: a
        central difference along f, the states moved by about STEP of their size (the
        look-ahead's step, 1e-8 of the run, left rounding noise of 5e-9 in the weight,
        which the field then carried: an implicit method on AMOD's slide, X' =
        AMOD(X, 1) - 0.5 held at 1, took steps of 1e-5). The surface is smooth there:
        its branches are frozen, and a level's is read on its edge."""
        if self.watched[k].gradient is not None:
            return self.surface_rate(k, t, y, f, m, z)
        # (and TIME by no more than STEP of the run -- a surface on TIME alone where
        # the states stand still -- nor by less than a thousand ulps of it: states at 0)
        span = self.lookahead_h / LOOKAHEAD
        h = STEP * span
        size = float(np.max(np.abs(f), initial=0.0))
        if size > 0.0:
            h = min(h, STEP * float(np.max(np.abs(y), initial=0.0)) / size)
        h = max(h, 1e3 * _EPS * max(abs(t), span))
        up = self.c.surf(t + h, (y + h * f).tolist(), m, z)[k]
        down = self.c.surf(t - h, (y - h * f).tolist(), m, z)[k]
        return (up - down) / (2.0 * h)

    # ------------------------------------------------------------------ restart
    def choose_modes(self, t: float, y: np.ndarray, z, m: list[float], at_zero: set[int],
                     first: bool = False, forced: dict[int, float] | None = None
                     ) -> list[float]:
        """Modes in force from t on.

        Surfaces known to be at zero here (a located crossing, a breakpoint, or
        exactly zero at the start) go the way the dynamics take them; every other
        surface takes the sign it has now (it may have jumped with a switch it
        depends on).
        """
        new = list(m)
        decided: set[int] = set(forced or ())
        for k, mode in (forced or {}).items():
            new[k] = mode
        # a sliding surface that another switch here moves off zero (a set point
        # stepped at a breakpoint, an INSW on a state) is slid on no longer: the values
        # it had before the switches, to tell that jump from the slide's own drift
        slid = self.c.surf(t, y.tolist(), m, z) if sliding_in(m) else None
        # A surface may depend on another switch's value (MODINT on STEP, say):
        # settle the signs again with the new branches until nothing moves.
        # (at the start the levels wait for a round of the signs: a start on a level's
        # edge reads the others' fields in their branches, not in the placeholder 0 --
        # RAMP(20) read as TIME - 20 made both levels of NINT(X) push X the same way)
        wait = first and bool(self.levels)
        for rounds in range(len(new) + 1 + wait):
            before = list(new)
            waiting = wait and rounds == 0
            lit = self.literal_here(t, y, new, z)
            if slid is not None and sliding_in(new):
                off = left_surfaces(slid, self.c.surf(t, y.tolist(), new, z),
                                    [k for k in self.sliding(new)
                                     if k not in at_zero and k not in decided])
                for k, side in off.items():
                    new[k] = side_mode(new[k], side, k in self.levels)
            if not waiting:
                # (level surfaces located at one instant on one edge -- two quantizers
                # that jump at the same X -- slide together where all their levels
                # below push back up and all above push back down)
                for k, edge in self._edges_together(t, y, new, z, at_zero, decided).items():
                    new[k] = edge
                    decided.add(k)
            # (a level's surface at zero: its argument stands on an edge, here where
            # another surface turned -- QNTZR(0.3, X) at X = 0.75 where STEP(0.75) --
            # and takes the level the motion goes to, as a located crossing does)
            on_edge = self.c.surf(t, y.tolist(), new, z) \
                if self.levels and not waiting and not first else None
            for k in range(len(new)):
                if k in self.levels:
                    edge = on_edge is not None and on_edge[k] == 0.0 and not slides(new[k])
                    # (one sliding on an edge stays there unless located anew)
                    if not waiting and k not in decided and (k in at_zero or first or edge or (
                            lit[k] != new[k] and not slides(new[k]))):
                        new[k] = self.level_ahead(k, t, y, new, z,
                                                  located=k in at_zero or edge)
                        if not edge or k in at_zero:  # (an edge may move with the others)
                            decided.add(k)
                    continue
                landed = lit[k] == 0.0 and new[k] != 0.0 and not slides(new[k])
                if k in at_zero or (first and lit[k] == 0.0) or landed:
                    # at zero: located there, started there, or jumped onto it with
                    # a switch it depends on
                    if k not in decided:
                        new[k] = self.direction(k, t, y, new, z, old=None if first else m[k])
                        decided.add(k)
                elif lit[k] != 0.0 and not slides(new[k]) and lit[k] != new[k]:
                    new[k] = lit[k]
            if new == before and not waiting:
                break
        return new

    def literal_here(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """The literal modes at (t, y) in the branches m; those of a surface read on
        some branches only (`Watched.guarded`: an ELSE IF's test) just after t, along
        the motion, as the program first reads them: at a located crossing of the
        test before it, or after a DISCRETE section moved the states, the point itself
        may be a rounding error either side of where the branch begins, and the test
        may have no value there (ELSE IF (LOG(X - 0.5) < -1) after IF (X <= 0.5), at
        X = 0.5)."""
        return self._ahead(self.c.modes_literal, t, y, m, z, lambda v: True)

    def surfaces_here(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """The surfaces at (t, y) in the branches m (a segment's start); a guarded one
        with no value there, its value just after it (`literal_here`)."""
        return self._ahead(self.c.surf, t, y, m, z, lambda v: not math.isfinite(v))

    def _ahead(self, fn, t: float, y: np.ndarray, m, z, undefined) -> list[float]:
        """fn at (t, y), its guarded entries for which `undefined(value)` holds (all,
        if fn fails there) taken just after t, along the motion."""
        guarded = [k for k, w in enumerate(self.watched) if w.guarded]
        try:
            here = list(fn(t, y.tolist(), m, z))
        except (ArithmeticError, ValueError):
            if not guarded:
                raise
            here = None
        if here is not None and not any(undefined(here[k]) for k in guarded):
            return here
        h = self.lookahead_h
        f = np.asarray(self.field(t, y, m, z), dtype=float)
        after = list(fn(t + h, (y + h * f).tolist(), m, z))
        if here is None:
            return after
        for k in guarded:
            if undefined(here[k]):
                here[k] = after[k]
        return here

    def after_memory(self, t: float, y: np.ndarray, m: list[float], z_before, z_after
                     ) -> list[float]:
        """Modes m, chosen with the memory z_before, once the memory is z_after (a
        restart updates it: a new day's weather, a sample held): a surface whose
        sign moved with it takes its new sign (or the way the motion goes, if the
        memory put it on zero); the others keep the modes they were given."""
        if list(z_before) == list(z_after):
            return m
        yl = y.tolist()
        before = self.c.modes_literal(t, yl, m, z_before)
        after = self.c.modes_literal(t, yl, m, z_after)
        return self._rechosen(t, y, z_after, m, {k: mode for k, mode in enumerate(m)
                                                 if before[k] == after[k]})

    def _rechosen(self, t: float, y: np.ndarray, z, m: list[float],
                  kept: dict[int, float]) -> list[float]:
        """m with the surfaces not in `kept` chosen anew at (t, y) (`after_memory`,
        `after_reset`); choose_modes takes a surface that is not triggered where its
        sign is, so the kept ones are forced (one just left by a slide, a few ulps on
        the other side, would flip back)."""
        if len(kept) == len(m):
            return m
        new = self.choose_modes(t, y, z, m, set(), forced=kept)
        return [kept.get(k, mode) for k, mode in enumerate(new)]

    def returning(self, t: float, y: np.ndarray, m, z, triggered) -> list[int]:
        """The memory triggers just crossed (of `triggered`, modes m) that the motion
        takes back at once: on the branch they crossed to, the surface's rate points
        back to where it came from. Its memory holds what that branch gave at this
        instant, and the trigger is back on its old side here too, not at the next
        step's end (X' = 1 - 2 ZHOLD(X - 1, TIME) holds TIME = 1 at X = 1 and turns
        X at once; going on in the new branch for a step held TIME = 1.03)."""
        ks = [k for k in triggered if k in self.memory_triggers and m[k] in (1.0, -1.0)]
        if not ks:
            return []
        f = np.asarray(self.field(t, y, m, z), dtype=float)
        return [k for k in ks if sign(self.surface_rate(k, t, y, f, m, z)) == -m[k]]

    def after_reset(self, t: float, y_before: np.ndarray, y: np.ndarray, m: list[float],
                    z) -> list[float]:
        """Modes m once a reset moved the states from y_before to y: a surface whose
        sign the reset moved takes its new one (MODINT's X1 = 1 - Y from 0 to 1 as Y
        is put back on its IC 0: it integrates again at once); the others keep theirs."""
        before = self.c.modes_literal(t, y_before.tolist(), m, z)
        after = self.c.modes_literal(t, y.tolist(), m, z)
        # (a surface left at zero by the crossing whose reset this is reads the reset
        # value already: off zero now, it takes its side)
        e = self.c.surf(t, y.tolist(), m, z)
        scale = 1e-12 * max(1.0, float(np.max(np.abs(y))) if len(y) else 1.0)
        return self._rechosen(t, y, z, m, {
            k: mode for k, mode in enumerate(m)
            if (before[k] == after[k] and not (mode == 0.0 and abs(e[k]) > scale))
            or self.watched[k].kind is not SurfaceKind.SIGN or slides(mode)})

    def direction(self, k: int, t: float, y: np.ndarray, m, z, old) -> float:
        """Which side of surface k the motion goes to from a point on it."""
        try:
            _, _, dp, dm = self.branch_rates(k, t, y, m, z)
        except (ArithmeticError, ValueError):
            # A branch may have no value on the surface itself (X/P at P = 0 in
            # X/FCNSW(P, P, 1., P)); there each function selects its X = 0 branch,
            # so the motion leaves the way those branches take it.
            m0 = self.at_zero(t, y, m, z)
            m0[k] = 0.0
            f0 = np.asarray(self.field(t, y, m0, z), dtype=float)
            return sign(self.surface_rate(k, t, y, f0, m0, z))
        way = leaving(dp, dm, exact=self.watched[k].gradient is not None)
        if way == STILL:
            # With other surfaces sliding, that is their compensation (two friction
            # terms on one velocity): this one slides with them and the joint
            # weights decide; else it stays at zero.
            others = any(slides(v) for j, v in enumerate(m) if j != k)
            return SLIDE if others and self.events else 0.0
        if way == REPELS:  # keep going the way it was going
            if old is not None and old != 0.0 and not slides(old):
                return -old
            return 1.0 if dp >= -dm else -1.0
        if way == SLIDES:
            if k in self.memory_triggers and old in (1.0, -1.0):
                # across: the memory takes the new branch's value, and the motion
                # goes on from there (Z = ZHOLD(X - 1, 1) in X' = 1 - 2 Z turns X at 1)
                return -old
            return SLIDE if self.events else 0.0
        return way if way in (UP, DOWN) else 0.0

    def at_zero(self, t: float, y: np.ndarray, m, z) -> list[float]:
        """m with every sign surface that is exactly zero at (t, y) in its X = 0
        branch (FSW's B), the branch the function is defined to take there: what a
        row at a switching instant shows, and what is evaluated on the surface
        when the branch in force has no value there."""
        lit = self.c.modes_literal(t, y.tolist(), m, z)
        return [0.0 if lit[k] == 0.0 and w.kind is SurfaceKind.SIGN and not slides(m[k])
                else m[k] for k, w in enumerate(self.watched)]

    def level_ahead(self, k: int, t: float, y: np.ndarray, m, z, located: bool = False
                    ) -> float:
        """QNTZR: the level the argument is at just after t; on an edge both levels
        push the argument back to (a crossing just `located` there, or a start on it),
        the edge itself: it slides there (QNTZR in a feedback loop)."""
        lit = self.c.modes_literal(t, y.tolist(), m, z)[k]
        edge = self._edge(k, t, y, m, z, lit, located)
        if edge is not None and self._pushed_back({k: edge}, t, y, m, z):
            return edge
        f = np.asarray(self.c.rhs(t, y.tolist(), m, z), dtype=float)
        h = self.lookahead_h
        ahead = self.c.modes_literal(t + h, (y + h * f).tolist(), m, z)[k]
        return ahead if abs(ahead - lit) <= 1 else lit

    def _edges_together(self, t: float, y: np.ndarray, m, z, at_zero: set[int],
                        decided: set[int]) -> dict[int, float]:
        """The level surfaces of `at_zero` (two or more, not yet decided) standing on
        their edges at (t, y) whose levels push back together -- the field with all of
        them below their edges raises every one, with all above lowers every one --
        and their edges: a slide on both at once. Each alone sees the other's level
        as it is, and neither pushes back (two quantizers of one X with an edge in
        common: the run chattered across it)."""
        ks = [k for k in at_zero if k in self.levels and k not in decided
              and not slides(m[k])]
        if len(ks) < 2:
            return {}
        lit = self.c.modes_literal(t, y.tolist(), m, z)
        edges = {}
        for k in ks:
            edge = self._edge(k, t, y, m, z, lit[k], True)
            if edge is None:
                return {}
            edges[k] = edge
        return edges if self._pushed_back(edges, t, y, m, z) else {}

    def _pushed_back(self, edges: dict[int, float], t: float, y: np.ndarray, m, z) -> bool:
        """Whether level surfaces standing on `edges` (surface -> its edge) slide there:
        the field with all of them in the level below raises every one, with all above
        lowers every one (each rate read on its edge: `_rated`). Not where a run takes
        no events, nor where a level has no value here."""
        if not self.events:
            return False
        on, above, below = list(m), list(m), list(m)
        for k, edge in edges.items():
            on[k], above[k], below[k] = edge, side_mode(edge, 1.0, True), \
                side_mode(edge, -1.0, True)
        above, below = self.follow(t, y, [above, below], z)
        try:
            f_up = np.asarray(self.field(t, y, above, z), dtype=float)
            f_down = np.asarray(self.field(t, y, below, z), dtype=float)
            return all(leaving(self.surface_rate(k, t, y, f_up, on, z),
                               self.surface_rate(k, t, y, f_down, on, z), exact=False) == SLIDES
                       for k in edges)
        except (ArithmeticError, ValueError):
            return False

    def _edge(self, k: int, t: float, y: np.ndarray, m, z, lit: float, located: bool
              ) -> float | None:
        """The edge of level `lit`'s band that level surface k's argument stands on at
        (t, y), if it does: the nearer one where a crossing was `located` here, else
        one it is on to rounding."""
        yl = y.tolist()
        above, below = list(m), list(m)
        above[k], below[k] = lit + 0.5, lit - 0.5
        try:
            up = self.c.surf(t, yl, above, z)[k]  # the argument less the upper edge
            down = self.c.surf(t, yl, below, z)[k]
        except (ArithmeticError, ValueError):
            return None
        off, edge = (up, lit + 0.5) if abs(up) <= abs(down) else (down, lit - 0.5)
        return edge if located or abs(off) <= 1e-12 * max(1.0, abs(edge)) else None

    def quiet(self, k: int, t: float, y: np.ndarray, m, z) -> bool:
        """True if surface k's branch does not change the derivatives here: a change
        of it is no event."""
        w = self.watched[k]
        # (a memory's condition changes nothing the derivatives see now, but what the
        # memory keeps is taken where it flips: located, as every switch)
        if w.purpose.stops or w.purpose is Purpose.MEMORY or w.kind is not SurfaceKind.SIGN \
                or k in self.reset_surfaces:
            return False
        mp, mm = list(m), list(m)
        mp[k], mm[k] = 1.0, -1.0
        yl = y.tolist()
        try:
            return self.c.rhs(t, yl, mp, z) == self.c.rhs(t, yl, mm, z) and \
                self.c.rhs(t, yl, [*m[:k], 0.0, *m[k + 1:]], z) == self.c.rhs(t, yl, mp, z)
        except (ArithmeticError, ValueError):
            return False

    def silent(self, k: int, t: float, y: np.ndarray, m, z) -> bool:
        """True if surface k's branch changes neither the derivatives here nor the
        side another watched surface is on: a crossing of it is followed without
        stopping. A switch that another's surface reads (ABS(Y) in INSW(ABS(Y) - DH,
        ...)) is quiet, and silent unless that surface is on another side because of
        it (crossed in the same step, or a relation's 1 become 0 under RSW): then the
        step is cut at its crossing, so the other is located or chosen again."""
        if not self.quiet(k, t, y, m, z):
            return False
        mp, mm = list(m), list(m)
        mp[k], mm[k] = 1.0, -1.0
        yl = y.tolist()
        try:
            ep, em = self.c.surf(t, yl, mp, z), self.c.surf(t, yl, mm, z)
        except (ArithmeticError, ValueError):
            return False
        return all(self.side(j, ep[j]) == self.side(j, em[j])
                   for j in self.watch_idx if j != k and not slides(m[j]))

    def side(self, k: int, e: float) -> float:
        """Where surface k's value e puts it: its sign, or for a level surface (its
        distance to the band's edges) whether it has left its band. A value that
        moves onto zero (RSW's condition, 1 or 0) changes side."""
        if self.watched[k].kind is SurfaceKind.LEVEL:
            return float(e < 0.0)
        return sign(e)

    def apply_resets(self, y: np.ndarray, m: list[float], t: float | None = None,
                     z=None) -> np.ndarray:
        """MODINT: hold the state at its IC while X1 <= 0 and X2 > 0. Given (t, z):
        also put each state where its function holds it (LIMINT on a bound)."""
        if self.c.settle is not None and t is not None:
            settled = np.array(self.c.settle(t, y.tolist(), m, z), dtype=float)
            if not np.array_equal(settled, y):
                y = settled
        for r in self.resets:
            m1 = m[r.first] if isinstance(r.first, int) else r.first
            m2 = m[r.second] if isinstance(r.second, int) else r.second
            if m1 <= 0 and m2 > 0:
                y = y.copy()
                y[r.state] = self.y0[r.state]
        return y

    # -------------------------------------------------------------- along a step
    def crossed(self, k: int, mode: float, e_b: float) -> bool:
        """Whether surface k, in `mode`, is on the wrong side at the step's end (a
        crossing that runs code, SCHEDULE's or an EVENT's, has when it reaches zero:
        X - 2 reaching 0 exactly at an output instant runs its code before that row)."""
        w = self.watched[k]
        if w.kind is SurfaceKind.LEVEL:
            return e_b < 0.0
        if mode > 0:
            return e_b < 0.0 or (e_b == 0.0 and w.purpose is Purpose.SCHEDULE)
        if mode < 0:
            return e_b > 0.0 or (e_b == 0.0 and w.purpose is Purpose.SCHEDULE)
        return False

    def locate(self, k: int, m, z, interp, ta: float, tb: float, segment_start: float,
               xtol: float | None = None) -> float | None:
        """Where in [ta, tb] surface k crossed, or None when the step began on the
        surface and was on the wrong side all along (nothing to bracket: the
        caller takes the surface's sign at tb instead of stopping at ta again).
        `xtol`: how close (default: a few ulps of TIME)."""
        from scipy.optimize import brentq

        def g(t):
            return self.c.surf(t, list(map(float, interp(t))), m, z)[k]

        ga = g(ta)
        gb = g(tb)
        if gb == 0.0:
            return tb
        if not math.isfinite(ga) and self.watched[k].guarded:
            ga = 0.0  # (a test that has no value where its branch begins: as on zero)
        if ga == 0.0 or sign(ga) == sign(gb):
            # The step began on the surface (a restart there): find where it had
            # left to the consistent side, and bracket the crossing from there.
            ta_new = None
            for j in range(1, 33):
                tj = ta + (tb - ta) * j / 32.0
                gj = g(tj)
                if not math.isfinite(gj):
                    continue
                if gj != 0.0 and sign(gj) != sign(gb):
                    ta_new = tj
                elif ta_new is not None:
                    break
            if ta_new is None:
                # on zero at ta and on the wrong side after: a crossing at ta, unless
                # ta is where the run just restarted (then stopping there again
                # would make no progress)
                return ta if ta > segment_start else None
            ta = ta_new
        return brentq(g, ta, tb, xtol=xtol or _XTOL * max(abs(tb), 1e-300), rtol=_XTOL,
                      maxiter=200)

    def slide_exits(self, m, t: float, y: np.ndarray, z) -> list[tuple[int, float]]:
        """The sliding surfaces whose motion leaves them here, and the branch it
        leaves to (a sign, or a level either side of the edge).

        With one surface sliding, the rates in its two branches are the surface's
        own and their signs are exact. With several, the others compensate, and a
        rate that they hold at zero comes out as rounding noise: a rate counts
        when it exceeds 1E-9 of the largest rate of any corner."""
        out = []
        for k in self.sliding(m):
            _, _, dp, dm = self.branch_rates(k, t, y, m, z)
            noise = self._rate_noise(k, t, y, m, z)
            if dp > noise:
                out.append((k, side_mode(m[k], 1.0, k in self.levels)))
            elif dm < -noise:
                out.append((k, side_mode(m[k], -1.0, k in self.levels)))
        return out

    def _rate_noise(self, k: int, t: float, y: np.ndarray, m, z) -> float:
        """Below this, a sliding surface's branch rate is the others' compensation."""
        slides = self.sliding(m)
        if len(slides) < 2:
            return 0.0
        rates = self._mix(t, y, m, z, slides, with_rates=True)[3]
        return 1e-9 * float(np.max(np.abs(rates[:, slides.index(k)])))

    def locate_slide_exit(self, k: int, mode: float, m, z, interp, ta: float, tb: float
                          ) -> float:
        """Where in [ta, tb] the motion leaves sliding surface k for the branch in
        `mode` (`slide_exits`)."""
        from scipy.optimize import brentq

        side = 1.0 if mode > m[k] else -1.0

        noise = self._rate_noise(k, tb, np.asarray(interp(tb), dtype=float), m, z)

        def g(t):
            _, _, dp, dm = self.branch_rates(k, t, np.asarray(interp(t), dtype=float), m, z)
            return (dp if side > 0 else -dm) - noise

        ga, gb = g(ta), g(tb)
        if ga > 0:
            # leaving already where the step starts: a switch there (a push on TIME at
            # a breakpoint) ended the slide at once; the exit is that instant (it was
            # put at the step's end, one step late)
            return ta
        if gb <= 0:
            return tb
        return brentq(g, ta, tb, xtol=_XTOL * max(abs(tb), 1e-300), maxiter=200)


def left_surfaces(before, now, sliding: list[int]) -> dict[int, float]:
    """The sliding surfaces (of `sliding`) that a switch or code moved off zero, and to
    which side: a value now a thousand times the one before, which sliding keeps at
    the integration's drift."""
    return {k: (1.0 if now[k] > 0 else -1.0) for k in sliding
            if now[k] != before[k] and abs(now[k]) > 1e3 * abs(before[k])}


def literal_modes(c, plan: RunPlan, t: float, y: list[float], m, z) -> list[float]:
    """The modes the tests read at (t, y), from the modes m: where a surface is read on
    some branches only (`Watched.guarded`: an ELSE IF's test), read again from the
    modes found until nothing moves, as the program reads its tests in turn (the
    step-point mode's branches, a flow's first ones)."""
    new = list(c.modes_literal(t, y, m, z))
    if any(w.guarded for w in plan.watched):
        for _ in range(len(new)):
            again = list(c.modes_literal(t, y, new, z))
            if again == new:
                break
            new = again
    return new


def crossings(plan: RunPlan, surfaces: list[np.ndarray], m) -> dict[int, np.ndarray]:
    """For each watched surface, at which of the instants given as columns (arrays
    of one length) it is on the other side of its mode: the rule of `crossed` over
    NumPy columns. Only the surfaces that cross somewhere are listed."""
    out = {}
    for k in plan.watch_idx:
        if slides(m[k]):  # (kept at zero by the motion, its exit watched apart)
            continue
        e = surfaces[k]
        w = plan.watched[k]
        if w.kind is SurfaceKind.LEVEL:
            bad = e < 0.0
        elif m[k] == 0:
            bad = e != 0.0
        elif w.purpose is Purpose.SCHEDULE:  # (reaching zero is crossing: `crossed`)
            bad = e <= 0.0 if m[k] > 0 else e >= 0.0
        else:
            bad = e < 0.0 if m[k] > 0 else e > 0.0
        if bad.any():
            out[k] = bad
    return out


def wrong_side(plan: RunPlan, surfaces: list[np.ndarray], m) -> np.ndarray:
    """Which of the instants given as columns have any surface crossed."""
    bad = np.zeros(len(surfaces[0]) if surfaces else 0, bool)
    for mask in crossings(plan, surfaces, m).values():
        bad |= mask
    return bad


class TooManySlides(Exception):
    """More surfaces slide at once than the corner combination allows."""

    def __init__(self, count: int) -> None:
        super().__init__(count)
        self.count = count
