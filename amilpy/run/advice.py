"""Method advice: notice, after a run, when an explicit variable-step method
worked much harder than an implicit one would have (a stiff model).

The probe integrates the first tenth of the run with the explicit method and
with METHOD AUTO (LSODA, which turns to its stiff method by itself), discarding
outputs, and compares right-hand-side evaluations. (Radau, the probe before the
tight default tolerances, needs 2.5 times the evaluations at RELERR 1e-10 that it
needs at 1e-6, where an explicit method held by stability needs the same.) It runs only when
the explicit run finished, was expensive in evaluations and actually slow (a
second of wall-clock time: the probe costs 20-60 % of the run, worth paying
only where advice can save time), and within the run's own limits: the
wall-clock time the run left, and its steps.
"""

from __future__ import annotations

from dataclasses import replace

from .. import ir
from ..result import Run
from ..routes import route_for
from . import Cache, Options, simulate

EXPENSIVE = 5_000  # right-hand-side evaluations before a probe is worth it
SLOW = 1.0  # seconds of wall-clock time a run must have taken before a probe
RATIO = 5.0  # how many times cheaper the implicit method must be to say so
PROBE_STEPS = 200_000


def stiffness_advice(model: ir.Model, spec: ir.RunSpec, run: Run, opts: Options,
                     cache: Cache | None = None) -> str | None:
    """A one-line note when METHOD AUTO would have been much cheaper, else None."""
    route = route_for(run.method)
    if route.fixed or not route.explicit or not run.ok or \
            run.stats.get("nfev", 0) < EXPENSIVE or run.stats.get("seconds", 0.0) < SLOW \
            or run.stats.get("stiff_from") is None:
        return None  # (only a run whose steps stability held: Hairer's stiffness test)
    left = None
    if opts.max_time is not None:
        left = opts.max_time - run.stats.get("seconds", 0.0)
        if left <= 0:
            return None
    # the run's length (ACSL form: a TERMT may end it, with no FINTIM given)
    length = spec.timer.get("FINTIM", run.t_end - (float(run.t[0]) if len(run.t) else 0.0))
    window = 0.1 * length
    # outputs: one variable on a coarse grid; the work is the integration
    probe_spec = replace(spec, timer={**spec.timer, "OUTDEL": window, "PRDEL": window},
                         reports=[])
    probe = replace(opts, method=run.method, fintim=window, start=None, progress=None,
                    max_steps=min(PROBE_STEPS, opts.max_steps), max_time=left)
    explicit = simulate(model, probe_spec, probe, cache)
    if left is not None:
        left -= explicit.stats["seconds"]
        if left <= 0:
            return None
    implicit = simulate(model, probe_spec, replace(probe, method="AUTO", max_time=left), cache)
    if not (explicit.ok and implicit.ok) or implicit.stats["nfev"] == 0:
        return None
    ratio = explicit.stats["nfev"] / implicit.stats["nfev"]
    if ratio < RATIO:
        return None
    return (f"stiff: METHOD AUTO took {ratio:.0f}x fewer evaluations than METHOD "
            f"{run.method} on a probe of the first {window:g} s "
            f"({implicit.stats['nfev']} against {explicit.stats['nfev']}): it switches to "
            "its stiff method by itself")
