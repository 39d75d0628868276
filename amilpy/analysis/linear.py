"""Linear modes: the DYNAMIC block linearised about a state, in the switch
branches in force there, and the eigenvalues and mode shapes of its Jacobian.

`linearise` is the way in: the Jacobian of `Flow.field` (the field a stepper
integrates, branches frozen, sliding surfaces combined): the model's own where it
can be had (exact to rounding), else by central differences with the step chosen
column by column (`Flow.linearise`, by the one rule of `run.jacobian.jacobian_at`;
its module states the accuracy). `Linearisation.error` is the differences'
estimate, relative to the largest entry of J (0 for the model's own).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..diagnostics import AmilError
from ..run import Flow, FlowFailed, State
from ..run.jacobian import MODEL

ZERO = 1e-8  # an eigenvalue below this fraction of the largest is a zero mode


@dataclass(frozen=True)
class Linearisation:
    jacobian: np.ndarray  # J[i, j] = d(dy_i/dt)/d y_j
    names: list[str]  # the states, in the order of J's rows and columns
    error: float  # estimated error of J, relative to its largest entry
    how: str = MODEL  # or run.jacobian.DIFFERENCES


def linearise(flow: Flow, state: State, t: float) -> tuple[np.ndarray, list[str]]:
    """The Jacobian of the vector field at `state`, `t` (branches as in `state`)
    and the state names of its rows and columns."""
    lin = jacobian(flow, state, t)
    return lin.jacobian, lin.names


def jacobian(flow: Flow, state: State, t: float) -> Linearisation:
    """`linearise` with its error estimate (see the module docstring)."""
    y = np.asarray(state.y, dtype=float)
    try:
        jac, error, how = flow.linearise(state, t)
    except (ArithmeticError, ValueError) as exc:
        raise AmilError(f"cannot linearise at TIME = {t:.9g}: {exc}") from None
    if not np.all(np.isfinite(jac)):
        bad = int(np.argwhere(~np.isfinite(jac))[0][1])
        raise AmilError(f"cannot linearise at TIME = {t:.9g}: the derivatives are not "
                        f"finite near {flow.state_names[bad]} = {y[bad]:g}")
    size = float(np.max(np.abs(jac))) if jac.size else 0.0
    return Linearisation(jac, flow.state_names,
                         float(np.max(error)) / size if size and len(error) else 0.0, how)


@dataclass(frozen=True)
class Mode:
    """One eigenvalue (a complex pair is one mode, Im > 0) and its shape."""

    eigenvalue: complex
    shape: np.ndarray  # complex, the largest component exactly 1
    zero: bool  # a rigid-body or cyclic mode: |eigenvalue| ~ 0

    @property
    def wn(self) -> float:
        """Natural frequency |lambda| [rad/s]."""
        return 0.0 if self.zero else abs(self.eigenvalue)

    @property
    def fhz(self) -> float:
        return self.wn / (2.0 * math.pi)

    @property
    def zeta(self) -> float:
        """Damping ratio -Re(lambda)/|lambda| (1 for a decaying real mode, < 0 growing)."""
        return math.nan if self.zero else -self.eigenvalue.real / abs(self.eigenvalue)


@dataclass(frozen=True)
class Modes:
    """The linear modes about the state at `time`."""

    time: float
    state: State
    names: list[str]
    jacobian: np.ndarray
    error: float  # the Jacobian's estimated relative error
    modes: list[Mode]  # zero modes first, then by natural frequency
    how: str = MODEL  # the Jacobian's source (see `Linearisation`)


def mode_list(jac: np.ndarray) -> list[Mode]:
    """The modes of a Jacobian: each complex pair once (Im > 0), zero modes first,
    then by natural frequency."""
    if not jac.size:
        return []
    if not np.all(np.isfinite(jac)):
        # (LAPACK would print its complaint on stdout and give up)
        raise FlowFailed("the Jacobian is not finite there (a derivative that overflows "
                         "or is NaN): no modes")
    values, vectors = np.linalg.eig(jac)
    top = float(np.max(np.abs(values)))
    out = []
    for k, lam in enumerate(values):
        if lam.imag < 0 and abs(lam.imag) > ZERO * top:
            continue
        zero = abs(lam) <= ZERO * top
        if not zero and abs(lam.imag) <= ZERO * top:
            lam = complex(lam.real, 0.0)
        v = vectors[:, k]
        v = v / v[int(np.argmax(np.abs(v)))]
        out.append(Mode(complex(lam), v, bool(zero)))
    return sorted(out, key=lambda m: (not m.zero, m.wn, m.eigenvalue.real))


def modes(model, at: float = 0.0, *, method: str | None = None, rtol: float | None = None,
          atol: float | None = None, progress=None, **params: float) -> Modes:
    """The modes of `model` (an api.Model) about its state at TIME `at`, reached
    by integrating the first run from its start (at its start when `at` is t0);
    `progress` as a run's (`Options.progress`) while it integrates."""
    flow = model.flow(method=method, rtol=rtol, atol=atol, **params)
    flow.opts.progress = progress
    state = flow.initial_state()
    t0 = state.t
    if at < t0:
        raise AmilError(f"--at {at:g} is before the run starts (TIME = {t0:g})")
    if at > t0:
        state, _ = flow.advance(state, t0, at)
        if state.t < at:
            raise AmilError(f"the run stops at TIME = {state.t:.9g}, before --at {at:g}")
    lin = jacobian(flow, state, at)
    return Modes(at, state, lin.names, lin.jacobian, lin.error, mode_list(lin.jacobian),
                 lin.how)
