"""IR -> Python syntax tree -> code object, once per run.

The model's data and INITIAL values are folded into the code as constants, so
the hot functions are straight-line float arithmetic. Generated code is built as
an `ast` tree (model text is never pasted into source) and its globals are only
the names the compiler puts there (`pytree.namespace`), with empty builtins: no
imports, no attributes. Each statement has its own line in the code object, so a
fault names its statement (`faults`).

Functions made for one run (all take plain lists of floats):
  rhs(t, y, m, z)              state derivatives under frozen modes m
  surf(t, y, m, z)             the watched switching surfaces
  out(t, y, m, z)              every recorded variable, only at output instants
  mem(t, y, m, mn, z)          memory values after an accepted step (m: the modes
                               the step was taken with, mn: the modes from now on)

Modules: `emit` (IR expressions -> Python expressions), `build` (the functions,
`Compiler` and `ModelCode`), `consts` (values known before the run), `faults`
(where a fault happened and what it was), `pytree` (helpers on Python trees).
"""

from __future__ import annotations

from .build import Compiler
from .consts import evaluate_constant, initial_values, parameter_names
from .emit import Setting
from .faults import FaultReport
from .modelcode import ModelCode, fault_line
from .pytree import namespace

NAMESPACE = namespace()  # as the library stands at import (benchmarks read it)

__all__ = ["ModelCode", "Compiler", "FaultReport", "NAMESPACE", "Setting", "evaluate_constant",
           "fault_line", "initial_values", "namespace", "parameter_names"]
