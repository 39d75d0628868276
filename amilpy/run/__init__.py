"""Running a checked model: the run as a flow map.

    prepare.py   constants, generated functions and the plan of one run; the Cache
    plan.py      RunPlan: route, TIMER values, Tolerances, grid, watched surfaces,
                 breakpoints (plain data, decided once)
    watch.py     SurfaceWatch: branches, crossings located on the dense output,
                 the branch to enter, sliding (slide.py: several surfaces at once)
    loop.py      Integrator: segments, steps, events, restarts, limits; its parts:
      cursor.py    where it stands (Cursor), Stop, what a step's watch found
      segment.py   a segment's vector field and stepper
      stepwatch.py an accepted step's checks and crossings, the rows inside it
      restarts.py  new branches, events, resets, chatter; a failure's outcome
      fastpaths.py the routes' fast paths, by what the stepper declares
    steppoint.py StepPoint: the classic fixed-step loop (step-point mode), its grid
                 and TIMER rules
    record.py    rows on the output grid, RANGE brackets, the Run
    simulate.py  simulate(): one run prepared and handed to its driver
    driver.py    the run from its start to its Run: RANGE located, TERMINAL
    code.py      written-order code at run time: what it reports, its faults, TERMINAL
    advice.py    the stiffness note after an expensive explicit run
    flow.py      Flow.advance(): the loop as a function, with its sensitivity
    variational.py  its monodromy by the variational equations and saltations
    grazing.py   a surface dipping across zero inside a step, found
    jacobian.py  the field's Jacobian (the one place it is made)
    dense.py     a step's dense output at several instants
    faults.py    the one phrasing of an arithmetic fault in generated code

The documented internal API: `simulate`, `Options`, `prepare` (with `Cache`
and `Prepared`), `Flow`, `State` and `FlowFailed`.
"""

from .flow import Flow, FlowFailed, State
from .plan import DEFAULTS, Options, RunPlan, Tolerances
from .prepare import Cache, Prepared, prepare
from .simulate import simulate

__all__ = ["DEFAULTS", "Cache", "Flow", "FlowFailed", "Options", "Prepared", "RunPlan", "State",
           "Tolerances", "prepare", "simulate"]
