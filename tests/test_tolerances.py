"""RELERR/ABSERR per state: vectors to the solvers, never collapsed to the smallest
value given; the printout header shows what applied."""

import math

import numpy as np
import pytest
from conftest import METHODS

import amilpy
from amilpy.routes import route_for
from amilpy.run import Options, Tolerances

# a fast oscillator (X, V) that needs many steps at a tight tolerance, and a slow
# decay Y that is cheap at any tolerance
LISTING = """X = INTGRL(1.0, V)
V = INTGRL(0.0, -2500.0*X)
Y = INTGRL(1.0, -Y)
TIMER FINTIM = 2.0, OUTDEL = 0.5
RELERR 1E-10
ABSERR 1E-12
{each}END
"""
VARIABLE = [m for m in METHODS if route_for(m).uses_tolerances]


@pytest.mark.parametrize("method", VARIABLE)
def test_per_state_relerr_reaches_the_solver(method):
    # Loosening the oscillator alone must cut the work several-fold while Y keeps
    # its own tight tolerance. With the old collapse to the smallest RELERR both
    # runs did the same work (3523 .. 64086 evaluations each).
    tight, = amilpy.loads(LISTING.format(each="")).run(method=method, advice=False)
    loose, = amilpy.loads(LISTING.format(each="RELERR X = 1E-4, V = 1E-4\n")).run(
        method=method, advice=False)
    assert loose.stats["nfev"] < 0.5 * tight.stats["nfev"]
    # Y at RELERR 1E-10 (1E-8: 100 tolerance units of slack); the oscillator at 1E-4
    # over 16 periods drifts to about 1E-3
    assert loose["Y"][-1] == pytest.approx(math.exp(-2.0), rel=1e-8)
    assert loose["X"][-1] == pytest.approx(math.cos(100.0), abs=1e-2)
    assert loose.settings == "RELERR 1e-10 (X 0.0001, V 0.0001), ABSERR 1e-12"


def test_tolerances_build_vectors_in_state_order():
    spec = amilpy.loads(LISTING.format(each="RELERR Y = 1E-6\nABSERR X = 1E-9\n")).ir.runs[0]
    tol = Tolerances.build(spec, Options(), ["V", "X", "Y"])
    assert list(tol.rtol) == [1e-10, 1e-10, 1e-6]
    assert list(tol.atol) == [1e-12, 1e-9, 1e-12]
    assert tol.describe() == "RELERR 1e-10 (Y 1e-06), ABSERR 1e-12 (X 1e-09)"
    # an option from outside replaces the listing's values, per-state ones included
    tol = Tolerances.build(spec, Options(rtol=1e-7), ["V", "X", "Y"])
    assert list(tol.rtol) == [1e-7] * 3 and tol.describe().startswith("RELERR 1e-07, ")
    assert np.array_equal(tol.atol, [1e-12, 1e-9, 1e-12])


def test_fixed_step_header_shows_delt():
    run, = amilpy.loads(LISTING.format(each="")).run(method="RK4", advice=False)
    assert run.settings.startswith("DELT ")
