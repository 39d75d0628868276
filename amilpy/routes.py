"""The integration routes: one row per route, every METHOD spelling that selects it.

This table is the only list of methods. The checker validates METHOD against it,
the command line's `--method` help is generated from it, the printout header asks
it whether RELERR/ABSERR apply, the advice asks which routes are explicit, and
`steppers.make_stepper` builds a route from its `stepper` name with the row's own
constants (the stability limit of an explicit method, a local tolerance). Adding
a SciPy solver is one row here plus, if it needs one, a stepper class.

Stdlib only: `amilpy check` reads this at start-up.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Route:
    name: str  # canonical name, as the printout header shows it
    aliases: tuple[str, ...]  # every METHOD spelling that selects it (name included)
    fixed: bool  # fixed step DELT (CSMP's rules); else variable step with RELERR/ABSERR
    explicit: bool  # an explicit method: its step is bounded by stability on stiff models
    stepper: str  # the stepper that runs it (see steppers.make_stepper)
    scipy: str | None  # the SciPy OdeSolver class, for the routes built on one
    summary: str  # one line for --help and the language reference
    # explicit methods: |h*lambda| where the stability region ends on the negative real
    # axis. A variable-step pair past it is bound by stability (Hairer's stiffness test);
    # a fixed-step method past it on a decaying mode makes that mode grow.
    stability_limit: float | None = None
    # the solver's own tolerance as a fraction of RELERR/ABSERR (see BDF's row)
    local_tolerance: float = 1.0
    # runs in step-point mode unless told otherwise (the classic translators' RECT)
    step_point: bool = False

    @property
    def uses_tolerances(self) -> bool:
        """RELERR/ABSERR apply (variable-step routes); DELT applies otherwise."""
        return not self.fixed


ROUTES: tuple[Route, ...] = (
    Route("AUTO", ("AUTO",), False, False, "odeint", "LSODA",
          "default: Fortran LSODA (odeint), stiff/non-stiff switching"),
    # Hairer's thresholds for DOPRI5 and DOP853: each pair's stability boundary
    Route("RK45", ("RKS", "RK45"), False, True, "scipy", "RK45",
          "variable-step Runge-Kutta 4(5), SciPy RK45", stability_limit=3.25),
    Route("DOP853", ("DOP853",), False, True, "scipy", "DOP853",
          "variable-step Dormand-Prince 8(5,3)", stability_limit=6.1),
    # the same pair compiled with the model by numba (the [fast] extra; without it, or
    # for a model with no compiled form, it runs as DOP853): amilpy.code
    Route("COMPILED", ("COMPILED", "DOP853C"), False, True, "compiled", "DOP853",
          "DOP853 compiled with the model by numba (pip install 'amilpy[fast]')",
          stability_limit=6.1),
    Route("LSODA", ("LSODA", "MILNE"), False, False, "scipy", "LSODA",
          "SciPy's LSODA class, step by step"),
    Route("RADAU", ("RADAU", "STIFF"), False, False, "scipy", "Radau",
          "implicit Runge-Kutta Radau IIA, order 5 (stiff models)"),
    # BDF advances with the solution whose error it estimates (no local extrapolation,
    # unlike RK45, DOP853 and Radau), so on a lightly damped mode its errors per step
    # add up: 25 tolerance units on the two-mass drive at K = 1E2, RELERR 1E-6, 77 at
    # 1E-9. A decade tighter locally keeps it within 4 (12 at 1E-9) for 15-40% more
    # evaluations; see docs/robustness.md.
    Route("BDF", ("BDF", "GEAR"), False, False, "scipy", "BDF",
          "backward differentiation formulas, orders 1-5 (stiff models)",
          local_tolerance=0.1),
    Route("RK4", ("RK4", "RKSFX", "SIMP"), True, True, "RK4", None,
          "fixed-step classic Runge-Kutta, order 4", stability_limit=2.785),
    Route("EULER", ("EULER", "RECT"), True, True, "Euler", None,
          "fixed-step Euler (rectangular), in step-point mode", stability_limit=2.0,
          step_point=True),
    Route("TRAPZ", ("TRAPZ", "HEUN"), True, True, "Heun", None,
          "fixed-step Heun (trapezoid predictor-corrector)", stability_limit=2.0),
    Route("ADAMS", ("ADAMS", "AB2"), True, True, "AdamsBashforth2", None,
          "fixed-step 2nd-order Adams-Bashforth", stability_limit=1.0),
)

BY_NAME: dict[str, Route] = {r.name: r for r in ROUTES}
# Every METHOD spelling -> its route.
METHODS: dict[str, Route] = {alias: r for r in ROUTES for alias in r.aliases}
DEFAULT = "AUTO"

# ACSL's ALGORITHM IALG = n -> the METHOD it runs as (contract section 11). IALG 3 is
# Euler in step-point mode (section 14): METHOD RECT here, the mode is the run's.
IALG_METHODS: dict[int, str] = {1: "LSODA", 2: "BDF", 3: "RECT", 4: "TRAPZ", 5: "RK4",
                                8: "RKS", 9: "RKS", 10: "BDF"}


class StepPointError(ValueError):
    """Step-point mode asked of a variable-step route."""


def step_point_mode(route: Route, asked: bool | None, method: str | None = None) -> bool:
    """Whether a run on `route` is in step-point mode: as asked (--step-point,
    step_point=, the listing's ALGORITHM IALG = 3 or DRIVER = 'EUDRIV'), else the
    route's default (EULER/RECT: on; the other fixed-step routes: located switching).
    Raises StepPointError when a variable-step route is asked for it."""
    if asked is None:
        return route.step_point
    if asked and route.uses_tolerances:
        fixed = ", ".join(r.aliases[0] for r in ROUTES if r.fixed)
        raise StepPointError(
            f"step-point mode needs a fixed-step method ({fixed}); METHOD "
            f"{(method or route.name).upper()} chooses its own steps")
    return asked


def route_for(method: str | None) -> Route | None:
    """The route a METHOD name selects (None: the default); None if unknown."""
    return METHODS.get((method or DEFAULT).upper())


def method_names() -> list[str]:
    """Every accepted METHOD spelling, sorted."""
    return sorted(METHODS)


def methods_help() -> str:
    """One line per route, its spellings first: the `--method` help text."""
    return "; ".join(f"{'/'.join(r.aliases)}: {r.summary}" for r in ROUTES)
