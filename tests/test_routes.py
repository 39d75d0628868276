"""The route registry is the one list of methods: the checker, the command line,
the printout header and the steppers all read it, so they cannot disagree."""

import numpy as np
import pytest

import amilpy
from amilpy import cli
from amilpy.output.printout import format_run
from amilpy.routes import METHODS, ROUTES, method_names, route_for
from amilpy.steppers import FIXED

LISTING = """X = INTGRL(1.0, -X)
TIMER FINTIM = 1.0, PRDEL = 0.5
METHOD {method}
END
"""


@pytest.mark.parametrize("spelling", sorted(METHODS))
def test_every_spelling_is_accepted_and_runs_its_route(spelling):
    route = route_for(spelling)
    run, = amilpy.loads(LISTING.format(method=spelling)).run(advice=False)
    assert run.ok
    # the printout header shows RELERR/ABSERR exactly when the route uses them
    # (METHOD HEUN used to print them for a fixed-step run)
    header = next(line for line in format_run(run).splitlines() if "METHOD" in line)
    assert ("RELERR" in header) == route.uses_tolerances, header


def test_unknown_method_lists_every_spelling():
    with pytest.raises(amilpy.AmilError) as err:
        amilpy.loads(LISTING.format(method="RUNGE"))
    hint = err.value.diagnostics[0].hint
    for name in method_names():
        assert name in hint


def test_cli_help_names_every_spelling(capsys):
    with pytest.raises(SystemExit):
        cli._parser().parse_args(["run", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    for name in method_names():
        assert name in out


def test_every_fixed_route_has_a_stepper_and_every_variable_one_a_solver():
    for r in ROUTES:
        if r.fixed:
            assert r.stepper in FIXED, r
        else:
            assert r.scipy is not None, r
        assert r.name in r.aliases


def test_bdf_takes_a_late_stiff_start_in_its_own_time():
    """A compartment that opens at TIME = 256063.56 with a rate of 1000 (X = U (1 -
    exp(-K (t - TC))) after): SciPy's BDF predicts over the step it meant and corrects
    over the one the floats give, and at that TIME a first step of 1e-9 is 20 ulps,
    1.5 % off: at RELERR 1e-9 / ABSERR 1e-12 it was rejected down to the floats'
    spacing (the Verner PFAS listing's IALG 2 at its conception event, until
    2026-12-01). Each segment now runs in a time of its own from 0. X at 0.04 after
    the opening against the closed form, to 1e-8 (the tolerance's order)."""
    listing = """TITLE A STIFF COMPARTMENT THAT OPENS LATE
PARAM TC = 256063.56, K = 1000.0, U = 10.0
X = INTGRL(0.0, FSW(TIME - TC, 0.0, K, K)*(U - X))
W = INTGRL(1.0, -1.0E-5*W)
METHOD BDF
RELERR X = 1.0E-9, W = 1.0E-9
ABSERR X = 1.0E-12, W = 1.0E-12
TIMER FINTIM = 256063.5602, OUTDEL = 256063.5601, PRDEL = 256063.5601
PRINT X, W
END
"""
    run, = amilpy.loads(listing, "late.amil").run(advice=False)
    assert run.ok, run.message
    t = run.times[-1]
    assert t == 256063.5602
    assert run["X"][-1] == pytest.approx(10.0 * -np.expm1(-1000.0 * (t - 256063.56)),
                                         abs=1e-8)
    assert run["W"][-1] == pytest.approx(np.exp(-1e-5 * t), rel=1e-7)
