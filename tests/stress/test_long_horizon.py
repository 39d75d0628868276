"""Undamped oscillator: amplitude drift per method (CI: 100 periods; the 1E4-period
run is benchmarks/stress.py)."""

import math

import numpy as np
import pytest

import amilpy
from stress import cases as C

PERIODS = 100
# |drift| allowed after 100 periods. The fixed-step methods with DELT = 1/32
# are not energy-preserving: Euler and Adams-Bashforth grow, RK4 decays.
DRIFT = {"AUTO": 2e-3, "RKS": 2e-4, "DOP853": 1e-4, "COMPILED": 1e-4, "LSODA": 2e-3,
         "RADAU": 1e-5,
         "BDF": 5e-4, "RK4": 3e-3}


@pytest.fixture(scope="module")
def model():
    return amilpy.loads(C.OSCILLATOR.format(periods=f"{PERIODS}.0"), name="osc.amil")


# RADAU over 10,000 periods takes about 25 s: run with the slow tests
@pytest.mark.parametrize("method", [pytest.param(m, marks=pytest.mark.slow) if m == "RADAU"
                                    else m for m in C.METHODS])
def test_amplitude_drift(model, method, record_property):
    r, = model.run(method=method)
    drift = C.amplitude_drift(r)
    record_property("drift", drift)
    assert r.status == "finished"
    if method in DRIFT:
        assert abs(drift) <= DRIFT[method], drift
        # the phase, too: x(t) = cos(2 pi t) at whole periods
        assert abs(r["X"][-1] - 1.0) <= 2 * DRIFT[method] + 1e-6
    elif method == "EULER":
        # explicit Euler on an undamped oscillator grows by sqrt(1 + (w h)^2) per step
        h = 0.5 / 16
        expected = (1 + (2 * math.pi * h) ** 2) ** (PERIODS / h / 2) - 1
        assert drift == pytest.approx(expected, rel=1e-6)
    else:  # TRAPZ (Heun) and ADAMS grow slowly
        assert 0 < drift < 5.0
    assert np.all(np.isfinite(r["X"]))
