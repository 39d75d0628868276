"""A step's dense output at several instants in one call where the interpolant
can (SciPy's, a polynomial in t), one by one otherwise (`Hermite`, odeint's)."""

from __future__ import annotations

import numpy as np
from scipy.integrate import DenseOutput


def sample(interp, times: np.ndarray) -> np.ndarray:
    """The states at `times`: an array (states x instants)."""
    if isinstance(interp, DenseOutput):
        return np.asarray(interp(np.asarray(times, dtype=float)), dtype=float)
    return np.column_stack([np.asarray(interp(t), dtype=float) for t in times])
