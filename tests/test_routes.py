"""The route registry is the one list of methods: the checker, the command line,
the printout header and the steppers all read it, so they cannot disagree."""

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
