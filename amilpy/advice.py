"""Method advice: notice, after a run, when an explicit variable-step method
worked much harder than an implicit one would have (a stiff model).

The probe integrates the first tenth of the run with the explicit method and
with Radau, discarding outputs, and compares right-hand-side evaluations
(Radau's include those of its finite-difference Jacobians). It runs only when
the explicit run was expensive, so a cheap run pays nothing.
"""

from __future__ import annotations

from dataclasses import replace

from . import ir
from .result import Run
from .routes import Route

EXPENSIVE = 5_000  # right-hand-side evaluations before a probe is worth it
RATIO = 5.0  # how many times cheaper the implicit method must be to say so


def stiffness_advice(model: ir.Model, spec: ir.RunSpec, run: Run, route: Route) -> str | None:
    """A one-line note when METHOD STIFF would have been much cheaper, else None."""
    from .runner import Options, simulate

    if route.fixed or not route.explicit or run.stats.get("nfev", 0) < EXPENSIVE:
        return None
    window = 0.1 * spec.timer["FINTIM"]
    # outputs: one variable on a coarse grid; the work is the integration
    probe_spec = replace(spec, timer={**spec.timer, "OUTDEL": window, "PRDEL": window})
    explicit = simulate(model, probe_spec, Options(method=run.method, rtol=run.rtol,
                                                   atol=run.atol, fintim=window,
                                                   max_steps=200_000))
    implicit = simulate(model, probe_spec, Options(method="RADAU", rtol=run.rtol,
                                                   atol=run.atol, fintim=window,
                                                   max_steps=200_000))
    if not (explicit.ok and implicit.ok) or implicit.stats["nfev"] == 0:
        return None
    ratio = explicit.stats["nfev"] / implicit.stats["nfev"]
    if ratio < RATIO:
        return None
    return (f"stiff: METHOD STIFF took {ratio:.0f}x fewer evaluations than METHOD "
            f"{run.method} on a probe of the first {window:g} s "
            f"({implicit.stats['nfev']} against {explicit.stats['nfev']}); "
            "METHOD AUTO switches by itself")
