"""One run of a checked model, from its start to its `Run`: `simulate` prepares
it and hands it to its driver (`driver._Run`, or the ACSL form's `acsl.AcslRun`).
"""

from __future__ import annotations

import time as _clock

from .. import ir
from ..result import Run
from .driver import _Run
from .plan import Options
from .prepare import Cache, prepare


def simulate(model: ir.Model, spec: ir.RunSpec, options: Options | None = None,
             cache: Cache | None = None) -> Run:
    """Integrate one run of a checked model. Faults in the data raise AmilError;
    a failing integration returns a Run with status FAILED and the rows so far.
    `cache` (an `api.Model`'s) keeps generated functions between runs."""
    opts = options or Options()
    started = _clock.perf_counter()
    if model.acsl is not None:
        from .acsl import AcslRun, prepare_acsl

        return AcslRun(model, spec, opts, prepare_acsl(model, spec, opts, cache),
                       started).run()
    return _Run(model, spec, opts, prepare(model, spec, opts, cache), started).run()
