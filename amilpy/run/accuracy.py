"""Is what a run printed the model's, or the integrator's? The run repeated with a
100 times smaller RELERR and ABSERR (a fixed-step method: a 4 times shorter DELT),
and the two compared on the output grid, variable by variable, and event by event.

A variable whose largest difference is a sizeable part of its own variation (a
ripple that changes with the tolerance) is said to be numerical; otherwise the
number of significant digits the two runs share is what the printout can be
trusted to. Events are paired in time order: a shift, or a different count (an
event that depends on the tolerance)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import ir
from ..result import Run

TIGHTER = 100.0  # RELERR and ABSERR divided by this
SHORTER = 4.0  # DELT divided by this, for a fixed-step method
NUMERICAL = 0.1  # a difference this share of a variable's variation: its variation is numerical


@dataclass(frozen=True)
class VariableCheck:
    """One printed variable: the largest difference between the two runs and where,
    the variable's size and variation, and the significant digits they share."""

    name: str
    largest: float
    at: float
    size: float  # max |value|
    variation: float  # max - min
    digits: int  # significant digits the two runs share (16: all)

    @property
    def numerical(self) -> bool:
        return self.variation > 0 and self.largest > NUMERICAL * self.variation


@dataclass(frozen=True)
class AccuracyCheck:
    """A run against itself with a tighter tolerance (or shorter DELT); in words:
    `output.words.accuracy_lines`."""

    label: str
    how: str  # "RELERR 1e-12, ABSERR 1e-15" or "DELT 2.5e-04": what the check ran with
    variables: tuple[VariableCheck, ...]
    events: int  # in the run ...
    events_tight: int  # ... and in the tighter one
    shift: float | None  # the largest shift of a paired event (None: no events)
    message: str = ""  # why the check could not be made, when it could not


def tightened(spec: ir.RunSpec, run: Run, fixed: bool) -> tuple[ir.RunSpec, dict, str]:
    """The run's spec and options changes for the check, and how to say it."""
    if fixed:
        from .plan import timer_values

        delt = timer_values(spec).get("DELT")  # (the listing's, or the one TIMER gives)
        if delt is None or not delt > 0:
            raise ValueError("the fixed-step method's DELT is not known")
        new = delt / SHORTER
        return replace(spec, timer={**spec.timer, "DELT": new}), {}, f"DELT {new:.3g}"
    rtol, atol = run.rtol / TIGHTER, run.atol / TIGHTER
    return spec, {"rtol": rtol, "atol": atol}, f"RELERR {rtol:.3g}, ABSERR {atol:.3g}"


def compare(run: Run, tight: Run, how: str, names: list[str]) -> AccuracyCheck:
    """The two runs on their common output grid."""
    rows, rows_tight = run.outdel_mask | run.prdel_mask, tight.outdel_mask | tight.prdel_mask
    grid, grid_tight = run.times[rows], tight.times[rows_tight]
    n = min(len(grid), len(grid_tight))
    if n == 0 or not np.array_equal(grid[:n], grid_tight[:n]):
        return AccuracyCheck(run.label, how, (), len(run.events), len(tight.events), None,
                             "the two runs have no output instants in common")
    checks = []
    for name in names:
        a, b = run.values[name][rows][:n], tight.values[name][rows_tight][:n]
        finite = np.isfinite(a) & np.isfinite(b)
        if not finite.any():
            continue
        diff = np.where(finite, np.abs(a - b), 0.0)
        k = int(np.argmax(diff))
        size = float(np.max(np.abs(b[finite])))
        variation = float(np.max(b[finite]) - np.min(b[finite]))
        largest = float(diff[k])
        digits = 16 if largest == 0 or size == 0 else \
            max(0, min(16, int(math.floor(-math.log10(largest / size)))))
        checks.append(VariableCheck(name, largest, float(grid[k]), size, variation, digits))
    shifts = [abs(e.time - f.time) for e, f in zip(run.events, tight.events, strict=False)]
    return AccuracyCheck(run.label, how, tuple(checks), len(run.events), len(tight.events),
                         max(shifts) if shifts else None)


def printed_names(run: Run) -> list[str]:
    """The variables the printout and the figures show, in their order (all the
    run's variables when the listing names none)."""
    names = [n for r in run.reports if r.kind in ("PRINT", "OUTPUT", "PRTPLT", "PLOT")
             for n in r.names]
    names = list(dict.fromkeys(n for n in names if n in run.values))
    return names or [n for n in run.values if n != "TIME"]
