"""A guard against grazings the run loop does not see: a surface that dips
across zero and back inside one accepted step (both ends on the same side).

The loop looks for crossings at the ends of each step, so an orbit that just
touches a contact (the hoist's teeth separating for a millisecond when its
amplitude passes MN/C2) keeps its branch through the dip; a flow map computed
that way is discontinuous where the dip grows deep enough to be seen, and a
Newton iteration on it stalls. `Grazing` samples the watched sign surfaces
inside every step on its dense output (SAMPLES instants, one vectorised call);
where a surface comes closest to zero at an inner sample, and close compared
with how far it moves over the step, that approach is located by Brent's method
on the dense output. A sample or an approach on the wrong side raises `Missed`;
`Flow.advance` then takes that step again in pieces of a sixteenth (and again,
if need be), so the dip becomes two located crossings. A surface whose branch
feeds nothing the states see there (the loop follows such a crossing without an
event) is left alone, and one that dips again in pieces ever smaller is given up
for the rest of the flow (`Flow.advance` counts).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from .dense import sample_step
from .plan import Purpose, RunPlan, SurfaceKind
from .record import column

SAMPLES = 7  # instants inside a step
CLOSE = 0.25  # an approach this close (of the surface's range over the step) is located


class Missed(Exception):
    """A surface dipped across zero inside the step [ta, tb]."""

    def __init__(self, ta: float, tb: float, y: np.ndarray, modes, memory, surface: int) -> None:
        super().__init__(f"surface {surface} crossed inside [{ta}, {tb}]")
        self.ta, self.tb, self.y = ta, tb, y
        self.modes, self.memory, self.surface = list(modes), list(memory), surface


class Grazing:
    """Observer of a flow: raises `Missed` (see the module)."""

    def __init__(self, c, plan: RunPlan, watch, ignore: set[int] = frozenset()) -> None:
        self.c, self.watch = c, watch
        self.watched = [k for k in plan.watch_idx
                        if plan.watched[k].kind is SurfaceKind.SIGN
                        and plan.watched[k].purpose is not Purpose.MEMORY and k not in ignore]
        self.fractions = np.arange(0, SAMPLES + 2) / (SAMPLES + 1)  # the ends too

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if not self.watched or not tb > ta:
            return
        times, ys = sample_step(interp, ta, tb, self.fractions)
        with np.errstate(all="ignore"):
            values = self.c.surf_v(times, list(ys), m, z)
        n = len(times)
        for k in self.watched:
            side = m[k]
            if side not in (1.0, -1.0):  # at zero or sliding: no side to stay on
                continue
            v = column(values[k], n) * side  # > 0 on the branch's side
            # (at the ends it may be zero by a hair on either side: a crossing
            # located there, where the step starts or was cut)
            i = int(np.argmin(v))
            if np.min(v[1:-1]) < 0 or (0 < i < n - 1 and v[i] <= CLOSE * (np.max(v) - v[i])
                                       and self._dips(k, side, times[i - 1], times[i + 1],
                                                      interp, m, z)):
                # a branch nothing reads now crosses silently in the loop too
                if not self.watch.silent(k, float(times[i]), ys[:, i], m, z):
                    raise Missed(ta, tb, np.asarray(interp(ta), dtype=float), m, z, k)

    def _dips(self, k: int, side: float, a: float, b: float, interp, m, z) -> bool:
        """Whether surface k's closest approach between a and b crosses zero."""
        surf = self.c.surf

        def g(t: float) -> float:
            return side * surf(t, np.asarray(interp(t), dtype=float).tolist(), m, z)[k]

        res = minimize_scalar(g, bounds=(a, b), method="bounded",
                              options={"xatol": 1e-9 * (b - a) + 1e-300})
        return bool(res.fun < 0)
