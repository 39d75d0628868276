"""The Jacobian as a stepper takes it: dense for a small model, banded (after a
reverse Cuthill-McKee renumbering of the states when that narrows the band) for
odeint on a large one, sparse for SciPy's BDF and Radau.

`SegmentJacobian` is d f / d y of one segment's vector field (the branches
frozen): its sparsity is known when the segment starts, its values come from
the model's generated Jacobian (`codegen.jacobian`) on each call.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

DENSE_UP_TO = 32  # states: a dense Jacobian (and LU) is cheaper than any bookkeeping
# A model whose structure is known without its Jacobian (a large one's: see
# codegen.build.EARLY_FROM) and whose band (renumbered) is at most DIFFERENCED_BAND
# wide: odeint differences the band itself, ml + mu + 1 evaluations of the
# right-hand side a Jacobian, and the model's Jacobian is never built (for the
# 10,000-mass chain that build took more time and memory than the run)
DIFFERENCED_BAND = 16


class SegmentJacobian:
    """d f / d y of one segment's vector field `fun`: the model's Jacobian (`model()`
    builds it, the first time it is needed) under the segment's modes m and memory
    z. Where the generated derivatives fault or are not finite at a point (0.5 /
    SQRT(X) at X = 0), that call takes central differences of `fun` instead."""

    def __init__(self, n: int, model: Callable[[], object], m, z, fun: Callable,
                 structure: Callable[[], tuple | None] | None = None) -> None:
        self.n, self._make, self.m, self.z, self.fun = n, model, m, z, fun
        self._model = None
        # structure() -> (rows, cols) of the entries that can be nonzero, where known
        # without the model's Jacobian (else None)
        self._structure = structure

    @property
    def model(self):
        """The model's Jacobian, or False where its equations have statements the
        differentiation does not follow (a unit's IF: every entry differenced)."""
        if self._model is None:
            try:
                self._model = self._make()
            except NotImplementedError:
                self._model = False
                self._full = (np.repeat(np.arange(self.n), self.n),
                              np.tile(np.arange(self.n), self.n))
        return self._model

    @property
    def rows(self) -> np.ndarray:
        return self.model.rows if self.model else self._full[0]

    @property
    def cols(self) -> np.ndarray:
        return self.model.cols if self.model else self._full[1]

    def values(self, t: float, y: np.ndarray) -> np.ndarray:
        if self.model:
            try:
                v = self.model.values(t, y.tolist(), self.m, self.z)
                if np.all(np.isfinite(v)):
                    return v
            except (ArithmeticError, ValueError):
                pass
        from ..codegen.jacobian import finite_difference

        return finite_difference(self.fun, t, y)[self.rows, self.cols]

    def dense(self, t: float, y: np.ndarray) -> np.ndarray:
        out = np.zeros((self.n, self.n))
        out[self.rows, self.cols] = self.values(t, y)
        return out

    def sparse(self, t: float, y: np.ndarray):
        from scipy.sparse import csc_matrix

        return csc_matrix((self.values(t, y), (self.rows, self.cols)), shape=(self.n, self.n))

    def for_scipy(self) -> Callable:
        """The `jac` of a SciPy OdeSolver: dense for small models, else sparse."""
        return self.dense if self.n <= DENSE_UP_TO else self.sparse

    def banded(self) -> Banded:
        """odeint's banded Jacobian: differenced by odeint itself (`Banded.differenced`)
        where the structure is known and the band narrow, else from the model's
        Jacobian."""
        found = self._structure() if self._structure is not None else None
        if found is not None:
            order, lower, upper = narrowest(self.n, *found)
            if lower + upper + 1 <= DIFFERENCED_BAND:
                return Banded(self, (order, lower, upper))
        return Banded(self)


class Banded:
    """odeint's banded Jacobian of a renumbered system: states in the order `order`
    (a reverse Cuthill-McKee order when it narrows the band), bands ml, mu."""

    def __init__(self, jac: SegmentJacobian, differenced: tuple | None = None) -> None:
        """`differenced`: (order, ml, mu) of a band odeint differences itself (no
        `dfun`), else the model's Jacobian gives the entries."""
        order, lower, upper = differenced or narrowest(jac.n, jac.rows, jac.cols)
        self.order = order  # new position k holds old state order[k]
        self.position = np.argsort(order)  # old state i sits at position[i]
        self.identity = bool(np.all(order == np.arange(jac.n)))
        self.ml, self.mu = lower, upper
        self.jac = jac
        self.differenced = differenced is not None
        if not self.differenced:
            self._band_rows = upper + self.position[jac.rows] - self.position[jac.cols]
            self._band_cols = self.position[jac.cols]

    def wrap(self, fun: Callable) -> Callable:
        """The vector field in the new order."""
        if self.identity:
            return fun
        order, position = self.order, self.position

        def f(t, yp):
            return np.asarray(fun(t, yp[position]), dtype=float)[order]
        return f

    def to_new(self, y: np.ndarray) -> np.ndarray:
        return y if self.identity else np.asarray(y)[..., self.order]

    def to_old(self, y: np.ndarray) -> np.ndarray:
        return y if self.identity else np.asarray(y)[..., self.position]

    def dfun(self, t: float, yp: np.ndarray) -> np.ndarray:
        """odeint's Dfun: out[mu + i - j, j] = d f_i / d y_j in the new numbering."""
        y = yp if self.identity else yp[self.position]
        out = np.zeros((self.ml + self.mu + 1, self.jac.n))
        out[self._band_rows, self._band_cols] = self.jac.values(t, y)
        return out


def narrowest(n: int, rows: np.ndarray, cols: np.ndarray, always: bool = False
              ) -> tuple[np.ndarray, int, int]:
    """The states' order that narrows the band of a Jacobian with entries at (rows,
    cols) -- a reverse Cuthill-McKee order where it is narrower, tried for models
    above DENSE_UP_TO states (or `always`) -- and its lower and upper bands: new
    position k holds old state order[k]."""
    order = np.arange(n)
    lower, upper = _band(rows, cols)
    if (always or n > DENSE_UP_TO) and lower + upper + 1 > 8:
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        pattern = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
        candidate = np.asarray(reverse_cuthill_mckee((pattern + pattern.T).tocsr(),
                                                     symmetric_mode=True))
        position = np.argsort(candidate)
        lo, up = _band(position[rows], position[cols])
        if lo + up < lower + upper:
            order, lower, upper = candidate, lo, up
    return order, lower, upper


def _band(rows: np.ndarray, cols: np.ndarray) -> tuple[int, int]:
    if not len(rows):
        return 0, 0
    d = rows - cols
    return int(max(d.max(), 0)), int(max(-d.min(), 0))
