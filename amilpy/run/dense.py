"""A step's dense output at several instants in one call where the interpolant
can (SciPy's, a polynomial in t), one by one otherwise (`Hermite`, odeint's); and
the observers of a flow's steps sharing one such call (`Observers`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.integrate import DenseOutput


def sample(interp, times) -> np.ndarray:
    """The states at `times`: an array (states x instants)."""
    if isinstance(interp, DenseOutput):
        return np.asarray(interp(np.asarray(times, dtype=float)), dtype=float)
    if isinstance(interp, Shared):  # (instants it does not hold: its interpolant's)
        return sample(interp.interp, times)
    return np.column_stack([np.asarray(interp(t), dtype=float) for t in times])


def sample_step(interp, ta: float, tb: float, fractions: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """(the instants ta + (tb - ta) * fractions, the states there): from the
    evaluation the step's observers share when `fractions` is one they declared
    (`Observers`), else from the interpolant."""
    if isinstance(interp, Shared):
        columns = interp.columns.get(id(fractions))
        if columns is not None and columns[0] is fractions:
            return interp.times[columns[1]], interp.states[:, columns[1]]
    times = ta + (tb - ta) * fractions
    return times, sample(interp, times)


class Shared:
    """One step's interpolant, evaluated once at every instant its observers
    declared (ta + (tb - ta) * f for their fractions f, the ends exactly ta and
    tb): `sample_step` reads those, a call at either end too; any other instant is
    asked of the interpolant itself. An evaluation of SciPy's dense output costs
    about as much for twenty instants as for one."""

    __slots__ = ("interp", "ta", "tb", "times", "states", "columns")

    def __init__(self, interp, ta: float, tb: float, fractions: np.ndarray,
                 columns: dict) -> None:
        self.interp, self.ta, self.tb, self.columns = interp, ta, tb, columns
        times = ta + (tb - ta) * fractions
        times[0], times[-1] = ta, tb  # (fractions run from 0 to 1)
        self.times = times
        self.states = sample(interp, times)

    def __call__(self, t):
        if np.ndim(t) == 0:
            if t == self.ta:
                return self.states[:, 0].copy()
            if t == self.tb:
                return self.states[:, -1].copy()
        return self.interp(t)


class Observers:
    """Observers of a flow's accepted steps, `observer(ta, tb, interpolant, modes,
    memory)`, called in order on one `Shared` interpolant: the instants each says
    it will look at (its `fractions` of the step, from 0 to 1, if it has them;
    read with `sample_step`) are evaluated together, once."""

    def __init__(self, observers: Sequence[Callable | None]) -> None:
        self.members = [o for o in observers if o is not None]
        own = [f for f in (getattr(o, "fractions", None) for o in self.members)
               if f is not None]
        inner = [o.columns for o in self.members if isinstance(o, Observers)]
        self.fractions = np.unique(np.concatenate([[0.0, 1.0], *own]))
        # id(fractions) -> (fractions, their columns in the shared evaluation)
        self.columns = {id(f): (f, np.searchsorted(self.fractions, f)) for f in own}
        for table in inner:
            self.columns.update({key: (f, np.searchsorted(self.fractions, f))
                                 for key, (f, _) in table.items()})

    def __call__(self, ta: float, tb: float, interp, m, z) -> None:
        if tb > ta and not isinstance(interp, Shared):
            interp = Shared(interp, ta, tb, self.fractions, self.columns)
        for observer in self.members:
            observer(ta, tb, interp, m, z)
