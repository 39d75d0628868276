"""amilpy: AMIL/CSMP-style continuous-simulation listings, run by SciPy.

Pipeline, one module per stage: parse (text -> syntax) -> check (-> IR) ->
codegen (-> Python callables) -> run (steppers, events) -> result -> printout/plot.
"""

from .api import Model, load, loads
from .diagnostics import AmilError, UsageError

__all__ = ["AmilError", "Event", "Model", "Run", "Status", "UsageError", "interact", "load",
           "loads"]
__version__ = "0.1.0"


def __getattr__(name: str):
    # result.py needs numpy; `amilpy check` should not pay for importing it
    if name in ("Event", "Run", "Status"):
        from . import result
        from .output.views import install

        install()  # (a Run made outside Model.run draws and shows itself too)
        return getattr(result, name)
    if name == "interact":  # (ipywidgets, an optional extra, only when asked for)
        from .output.sliders import interact

        return interact
    raise AttributeError(f"module 'amilpy' has no attribute {name!r}")
