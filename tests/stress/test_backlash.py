"""Dead-zone oscillator, backlash width 1E-9..1 rad: period and event count."""

import numpy as np
import pytest

import amilpy
from stress import cases as C

GAPS = [1e-9, 1e-6, 1e-3, 1e-1, 1.0]
FINTIM = 20.0
# relative period error allowed: 10x RELERR for the variable-step methods; the
# fixed-step methods (DELT = 0.1/16) by their order
PERIOD_TOL = {**{m: 1e-5 for m in C.VARIABLE}, "RK4": 1e-8, "TRAPZ": 1e-4, "ADAMS": 1e-4,
              "EULER": 2e-2}


@pytest.fixture(scope="module")
def model():
    return amilpy.loads(C.DEAD_ZONE.format(fintim=FINTIM), name="dead_zone.amil")


@pytest.mark.parametrize("method", C.METHODS)
@pytest.mark.parametrize("gap", GAPS, ids=lambda g: f"gap{g:.0e}")
def test_dead_zone_period(model, gap, method):
    r, = model.run(method=method, GAP=gap)
    assert r.status == "finished", r.message
    expected = C.dead_zone_events(gap, FINTIM)
    times = [e.time for e in r.events]
    assert len(times) == len(expected), (times, expected)
    tol = PERIOD_TOL[method]
    # every crossing of +-GAP/2 where it should be (the error grows with time)
    assert np.max(np.abs(np.array(times) - expected)) <= tol * FINTIM
    # the period from like crossings
    first = r.events[0].surface
    same = [e.time for e in r.events if e.surface == first and e.old > 0 > e.new]
    period = np.diff(same)
    assert len(period) >= (1 if gap == 1.0 else 2)
    assert np.max(np.abs(period / C.dead_zone_period(gap) - 1.0)) <= tol
