"""amilpy: AMIL/CSMP-style continuous-simulation listings, run by SciPy.

Pipeline, one module per stage: parse (text -> syntax) -> check (-> IR) ->
codegen (-> Python callables) -> runner (steppers, events) -> result -> printout/plot.
"""

from .api import Model, load, loads
from .diagnostics import AmilError
from .result import Event, Run, Status

__all__ = ["AmilError", "Event", "Model", "Run", "Status", "load", "loads"]
__version__ = "0.1.0"
