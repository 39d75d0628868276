"""A guard against grazings the run loop does not see: a surface that dips
across zero and back inside one accepted step (both ends on the same side).

The loop looks for crossings at the ends of each step, so an orbit that just
touches a contact (the hoist's teeth separating for a millisecond when its
amplitude passes MN/C2) keeps its branch through the dip; a flow map computed
that way is discontinuous where the dip grows deep enough to be seen, and a
Newton iteration on it stalls. `Grazing` samples the watched sign surfaces
inside every step on its dense output (SAMPLES instants, one vectorised call)
and raises `Missed` on a sample on the wrong side; `Flow.advance` then takes
that step again in pieces of a sixteenth (and again, if need be), so the dip
becomes two located crossings. A dip shorter than the pieces' sampling is
still missed; its depth is then below about 1/(16*8)^2 of the surface's
excursion over the step.
"""

from __future__ import annotations

import numpy as np

from .dense import sample
from .loop import column
from .plan import Purpose, RunPlan, SurfaceKind

SAMPLES = 7  # instants inside a step


class Missed(Exception):
    """A surface dipped across zero inside the step [ta, tb]."""

    def __init__(self, ta: float, tb: float, y: np.ndarray, modes, memory, surface: int) -> None:
        super().__init__(f"surface {surface} crossed inside [{ta}, {tb}]")
        self.ta, self.tb, self.y = ta, tb, y
        self.modes, self.memory, self.surface = list(modes), list(memory), surface


class Grazing:
    """Observer of a flow: raises `Missed` (see the module)."""

    def __init__(self, c, plan: RunPlan) -> None:
        self.c = c
        self.watched = [k for k in plan.watch_idx
                        if plan.watched[k].kind is SurfaceKind.SIGN
                        and plan.watched[k].purpose is not Purpose.MEMORY]
        self.fractions = np.arange(1, SAMPLES + 1) / (SAMPLES + 1)

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if not self.watched or not tb > ta:
            return
        times = ta + (tb - ta) * self.fractions
        ys = sample(interp, times)
        with np.errstate(all="ignore"):
            values = self.c.surf_v(times, list(ys), m, z)
        n = len(times)
        # only a surface off zero (mode +-1) has a side to be on
        signs = np.array([m[k] if m[k] in (1.0, -1.0) else 0.0 for k in self.watched])[:, None]
        wrong = np.vstack([column(values[k], n) for k in self.watched]) * signs < 0
        if wrong.any():
            k = self.watched[int(np.argmax(wrong.any(axis=1)))]
            raise Missed(ta, tb, np.asarray(interp(ta), dtype=float), m, z, k)
