"""Integrator routes behind one contract (see `steppers.base` for it).

`make_stepper` builds the stepper a route's row in `routes.ROUTES` names, with
the row's constants (stability limit, local tolerance): the run loop asks for a
route by name and never by class.
"""

from __future__ import annotations

import math

import numpy as np

from ..routes import BY_NAME
from .base import Chunked, Hermite, Rhs, StepFailure, Stepper, Stiffness, first_bad
from .fixed import RK4, AdamsBashforth2, Clock, Euler, FixedStepper, Heun
from .ivp import ScipyStepper, solver_tolerance
from .jacobian import SegmentJacobian
from .odeint import LOG_BUDGET, UNLIMITED, Evaluations, OdeintStepper

# The fixed-step classes by the name a route's `stepper` field gives.
FIXED: dict[str, type[FixedStepper]] = {
    cls.__name__: cls for cls in (RK4, Euler, Heun, AdamsBashforth2)}

__all__ = ["LOG_BUDGET", "Chunked", "Clock", "Evaluations", "FIXED", "Hermite",
           "OdeintStepper", "Rhs", "ScipyStepper", "SegmentJacobian", "StepFailure", "Stepper",
           "Stiffness", "first_bad", "make_stepper", "solver_tolerance"]


def make_stepper(route: str, fun: Rhs, t0: float, y0: np.ndarray, t_bound: float, *,
                 rtol: np.ndarray, atol: np.ndarray, delt: float, max_step: float = math.inf,
                 first_step: float | None = None, checks=None, chunk: int = 16,
                 max_steps: int = UNLIMITED, expect: float | None = None,
                 jac: SegmentJacobian | None = None, kernel=None,
                 log: Evaluations | None = None, watch=None,
                 chunk_seconds: float | None = None) -> Stepper:
    """The stepper for a canonical route name (see `routes.ROUTES`).

    `rtol`, `atol`: per-state tolerances (variable-step routes); `delt`: the fixed
    step; `checks`: the instants the loop looks at (the output grid), which only
    the odeint stepper uses (without them AUTO runs on SciPy's LSODA class, which
    sees every step); `max_steps`: the steps the loop still allows; `expect`: how
    long after t0 the loop expects the next event (odeint sizes its first chunk so);
    `jac`: the vector field's Jacobian, for the implicit routes (None: differences);
    `kernel`: for the compiled route, its `KernelStepper` arguments (None: the route
    runs on its SciPy class); `log`, `watch`: the odeint stepper's evaluation log and
    surface check (see `OdeintStepper`); `chunk_seconds`: the wall-clock one odeint
    call may take (under a time limit).
    """
    r = BY_NAME[route]
    if len(y0) == 0:
        return Clock(t0, t_bound, min(max_step, delt) if r.fixed else max_step)
    if r.fixed:
        return FIXED[r.stepper](fun, t0, y0, t_bound, delt, r.stability_limit)
    rtol = np.asarray(rtol, dtype=float) * r.local_tolerance
    atol = np.asarray(atol, dtype=float) * r.local_tolerance
    if r.stepper == "odeint" and checks is not None:
        return OdeintStepper(fun, t0, y0, t_bound, checks, rtol=rtol, atol=atol,
                             max_step=max_step, first_step=first_step, chunk=chunk,
                             max_steps=max_steps, expect=expect, jac=jac, log=log,
                             watch=watch, chunk_seconds=chunk_seconds)
    if r.stepper == "compiled" and kernel is not None:
        from .compiled import KernelStepper

        return KernelStepper(kernel.pop("kernel"), fun, t0, y0, t_bound, rtol=rtol, atol=atol,
                             max_step=max_step, first_step=first_step, max_steps=max_steps,
                             **kernel)
    return ScipyStepper(r.scipy, fun, t0, y0, t_bound, rtol=rtol, atol=atol, max_step=max_step,
                        first_step=first_step, stability_limit=r.stability_limit, jac=jac)
