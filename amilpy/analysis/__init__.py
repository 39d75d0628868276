"""Beyond time histories: linear modes, periodic steady states by shooting, and
response curves by continuation, all on the run loop as a flow map
(`amilpy.run.Flow`: switches located, their saltations in the monodromy).

    linear.py    modes(): the Jacobian of the DYNAMIC block (`linearise`) in the
                 branches in force, its eigenvalues, frequencies, damping, shapes
    problem.py   the shooting problem: what closes a period (a period, or an
                 angle's advance), cyclic and free states, symmetries, residual
    periodic.py  periodic(): settle, then Newton on the period map; Orbit
    measure.py   minimum, maximum and mean of variables over a period
    response.py  response(): arclength continuation of the orbit in a data value
    folds.py     folds located, other losses of stability flagged

`Model.modes`, `Model.periodic` and `Model.response` (amilpy.api) are the way in;
the command line's `amilpy modes`, `periodic` and `response` print and write
what these return (amilpy.output.analysis).
"""

from .linear import Mode, Modes, linearise
from .periodic import NotConverged, Orbit
from .problem import Closure
from .response import Point, Response

# the functions are analysis.linear.modes, analysis.periodic.periodic and
# analysis.response.response (named like their modules, so not re-exported here)
__all__ = ["Closure", "Mode", "Modes", "NotConverged", "Orbit", "Point", "Response",
           "linearise"]
