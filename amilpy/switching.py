"""Switching rules: which branch each surface is in, and where it changes.

Used by the runner (`runner._Simulation` mixes this in; it provides `c`, the
compiled functions, `sf`, the surfaces' bookkeeping, `model`, `opts` and
`lookahead_h`). Everything here is about surfaces, never about stepping:

- `choose_modes`: the branches in force from an instant on. A surface at zero
  there goes the way the dynamics take it (`direction`: the sign of its rate in
  each branch); both branches pushing it back to zero means sliding (Filippov).
- `filippov`: the convex combination of the two vector fields that keeps a
  sliding surface at zero.
- `crossed`, `locate`: whether a step crossed a surface, and where (Brent's
  method on the dense output).
- `silent`: whether a surface's branch changes the derivatives at all now.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .surfaces import sign

SLIDE = 0.5  # not a sign (-1, 0, 1) nor a QNTZR level (an integer)


@dataclass
class _Surfaces:
    """Bookkeeping of the watched surfaces during a run."""

    kinds: list[str]
    purposes: list[str]
    descriptions: list[str]
    gradients: list[np.ndarray | None]  # d e/d y when the surface is linear in states
    breakpoint_only: list[bool]  # affine in TIME: handled as breakpoints


class Switching:
    def branch_rates(self, k: int, t: float, y: np.ndarray, m, z):
        """Both branches of surface k: their vector fields f+ and f-, and the
        surface's rate along each (d+, d-)."""
        mp, mm = list(m), list(m)
        mp[k], mm[k] = 1.0, -1.0
        yl = y.tolist()
        fp = np.asarray(self.c.rhs(t, yl, mp, z), dtype=float)
        fm = np.asarray(self.c.rhs(t, yl, mm, z), dtype=float)
        return (fp, fm, self.surface_rate(k, t, y, fp, mp, z),
                self.surface_rate(k, t, y, fm, mm, z))

    def filippov(self, k: int, t: float, y: np.ndarray, m, z):
        """f+, f- and the weight of f+ that keeps a sliding surface at zero."""
        fp, fm, dp, dm = self.branch_rates(k, t, y, m, z)
        denom = dm - dp
        alpha = 0.5 if denom == 0 else min(1.0, max(0.0, dm / denom))
        return fp, fm, alpha

    def surface_rate(self, k: int, t: float, y: np.ndarray, f: np.ndarray, m, z) -> float:
        """d e_k/dt along f: exact for surfaces linear in the states, else a difference."""
        g = self.sf.gradients[k]
        if g is not None:
            return float(g @ f)
        h = self.lookahead_h
        e0 = self.c.surf(t, y.tolist(), m, z)[k]
        e1 = self.c.surf(t + h, (y + h * f).tolist(), m, z)[k]
        return (e1 - e0) / h

    # ------------------------------------------------------------ restart
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
        # A surface may depend on another switch's value (MODINT on STEP, say):
        # settle the signs again with the new branches until nothing moves.
        for _ in range(len(new) + 1):
            before = list(new)
            lit = self.c.modes_literal(t, y.tolist(), new, z)
            for k in range(len(new)):
                if self.sf.kinds[k] == "level":
                    if k not in decided and (k in at_zero or first or lit[k] != new[k]):
                        new[k] = self.level_ahead(k, t, y, new, z)
                        decided.add(k)
                    continue
                landed = lit[k] == 0.0 and new[k] not in (0.0, SLIDE)
                if k in at_zero or (first and lit[k] == 0.0) or landed:
                    # at zero: located there, started there, or jumped onto it with
                    # a switch it depends on
                    if k not in decided:
                        new[k] = self.direction(k, t, y, new, z, old=None if first else m[k])
                        decided.add(k)
                elif lit[k] != 0.0 and new[k] != SLIDE and lit[k] != new[k]:
                    new[k] = lit[k]
            if new == before:
                break
        return new

    def silent(self, k: int, t: float, y: np.ndarray, m, z) -> bool:
        """True if surface k's branch does not change the derivatives here."""
        if self.sf.purposes[k] in ("finish", "termt") or self.sf.kinds[k] != "sign":
            return False
        mp, mm = list(m), list(m)
        mp[k], mm[k] = 1.0, -1.0
        yl = y.tolist()
        try:
            return self.c.rhs(t, yl, mp, z) == self.c.rhs(t, yl, mm, z) and \
                self.c.rhs(t, yl, [*m[:k], 0.0, *m[k + 1:]], z) == self.c.rhs(t, yl, mp, z)
        except (ArithmeticError, ValueError):
            return False

    def direction(self, k: int, t: float, y: np.ndarray, m, z, old) -> float:
        """Which side of surface k the motion goes to from a point on it."""
        _, _, dp, dm = self.branch_rates(k, t, y, m, z)
        tiny = 1e-300
        scale = max(abs(dp), abs(dm))
        if scale <= tiny or (abs(dp) <= 1e-13 * scale and abs(dm) <= 1e-13 * scale):
            return 0.0
        # noise level of a rate computed by differences
        eps = 0.0 if self.sf.gradients[k] is not None else 1e-9 * scale
        up, down = dp > eps, dm < -eps
        if up and down:  # repelling: keep going the way it was going
            if old is not None and old != 0.0 and old != SLIDE:
                return -old
            return 1.0 if dp >= -dm else -1.0
        if up:
            return 1.0
        if down:
            return -1.0
        if dp < -eps and dm > eps and self.opts.events:
            return SLIDE
        return 0.0

    def level_ahead(self, k: int, t: float, y: np.ndarray, m, z) -> float:
        """QNTZR: the level the argument is at just after t."""
        lit = self.c.modes_literal(t, y.tolist(), m, z)[k]
        f = np.asarray(self.c.rhs(t, y.tolist(), m, z), dtype=float)
        h = self.lookahead_h
        ahead = self.c.modes_literal(t + h, (y + h * f).tolist(), m, z)[k]
        return ahead if abs(ahead - lit) <= 1 else lit

    def apply_resets(self, y: np.ndarray, m: list[float]) -> np.ndarray:
        """MODINT: hold the state at its IC while X1 <= 0 and X2 > 0."""
        pos = {i: k for k, i in enumerate(self.c.watched)}
        for si, s in enumerate(self.model.states):
            if s.reset_surfaces:
                s1, s2 = s.reset_surfaces
                m1 = self.c.const_modes.get(s1, m[pos[s1]] if s1 in pos else 0.0)
                m2 = self.c.const_modes.get(s2, m[pos[s2]] if s2 in pos else 0.0)
                if m1 <= 0 and m2 > 0:
                    y = y.copy()
                    y[si] = self.c.y0[si]
        return y

    # ------------------------------------------------------------------ run
    def crossed(self, k: int, mode: float, e_a: float, e_b: float) -> bool:
        if self.sf.kinds[k] == "level":
            return e_b < 0.0
        if mode > 0:
            return e_b < 0.0
        if mode < 0:
            return e_b > 0.0
        return False

    def locate(self, k, m, z, interp, ta, tb, e_a, e_b) -> float | None:
        """Where in [ta, tb] surface k crossed, or None when the step began on the
        surface and was on the wrong side all along (nothing to bracket: the
        caller takes the surface's sign at tb instead of stopping at ta again)."""
        from scipy.optimize import brentq

        def g(t):
            return self.c.surf(t, list(map(float, interp(t))), m, z)[k]

        ga = g(ta)
        gb = g(tb)
        if gb == 0.0:
            return tb
        if ga == 0.0 or sign(ga) == sign(gb):
            # The step began on the surface (a restart there): find where it had
            # left to the consistent side, and bracket the crossing from there.
            ta_new = None
            for j in range(1, 33):
                tj = ta + (tb - ta) * j / 32.0
                gj = g(tj)
                if gj != 0.0 and sign(gj) != sign(gb):
                    ta_new = tj
                elif ta_new is not None:
                    break
            if ta_new is None:
                # on zero at ta and on the wrong side after: a crossing at ta, unless
                # ta is where the run just restarted (then stopping there again
                # would make no progress)
                return ta if ta > self.segment_start else None
            ta = ta_new
        return brentq(g, ta, tb, xtol=4 * np.finfo(float).eps * max(abs(tb), 1e-300),
                      rtol=4 * np.finfo(float).eps, maxiter=200)

    def slide_exits(self, m, t, y, z) -> list[tuple[int, float]]:
        out = []
        for k, v in enumerate(m):
            if v == SLIDE:
                _, _, dp, dm = self.branch_rates(k, t, y, m, z)
                if dp > 0:
                    out.append((k, 1.0))
                elif dm < 0:
                    out.append((k, -1.0))
        return out

    def locate_slide_exit(self, k, sign, m, z, interp, ta, tb) -> float:
        from scipy.optimize import brentq

        def g(t):
            _, _, dp, dm = self.branch_rates(k, t, np.asarray(interp(t), dtype=float), m, z)
            return dp if sign > 0 else -dm

        ga, gb = g(ta), g(tb)
        if ga > 0 or gb <= 0:
            return tb
        return brentq(g, ta, tb, xtol=4 * np.finfo(float).eps * max(abs(tb), 1e-300),
                      maxiter=200)
